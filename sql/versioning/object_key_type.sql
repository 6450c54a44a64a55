-- tgsis.object_key_type(table): the type of a versioned table's object key column, as SQL (format_type).
-- Keys travel as text between tgsis's functions; statements on storage cast
-- them back to this type, so that the key's index serves the lookup. A model
-- table stored in chunks (issue 40) has no <table>_ver: its <table>_chunk
-- keeps the object key column of the same type.
CREATE FUNCTION tgsis.object_key_type(p_t tgsis.versioned_tables)
RETURNS text
LANGUAGE sql
STABLE
AS $$
    SELECT pg_catalog.format_type(a.atttypid, a.atttypmod)
      FROM pg_catalog.pg_attribute a
     WHERE a.attrelid = coalesce(pg_catalog.to_regclass(pg_catalog.format('%I.%I', p_t.schemaname, p_t.tablename || '_ver')),
                                 pg_catalog.to_regclass(pg_catalog.format('%I.%I', p_t.schemaname, p_t.tablename || '_chunk')))
       AND a.attname = p_t.objectkeyfield AND NOT a.attisdropped
$$;

COMMENT ON FUNCTION tgsis.object_key_type(tgsis.versioned_tables) IS
    'the SQL type of the object key column of a versioned table''s <table>_ver storage, or of its <table>_chunk when stored in chunks (keys as text are cast back to it)';
