-- tgsis.object_key_type(table): the type of a versioned table's object key column, as SQL (format_type).
-- Keys travel as text between tgsis's functions; statements on storage cast
-- them back to this type, so that the key's index serves the lookup.
CREATE FUNCTION tgsis.object_key_type(p_t tgsis.versioned_tables)
RETURNS text
LANGUAGE sql
STABLE
AS $$
    SELECT pg_catalog.format_type(a.atttypid, a.atttypmod)
      FROM pg_catalog.pg_attribute a
     WHERE a.attrelid = (SELECT tgsis.storage_table(p_t.schemaname, p_t.tablename)::regclass)  -- once, not per catalog row
       AND a.attname = p_t.objectkeyfield AND NOT a.attisdropped
$$;

COMMENT ON FUNCTION tgsis.object_key_type(tgsis.versioned_tables) IS
    'the SQL type of the object key column of a versioned table''s <table>_ver storage (keys as text are cast back to it)';
