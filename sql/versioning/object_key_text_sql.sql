-- tgsis.object_key_text_sql(table, alias): the SQL expression of the canonical text of a versioned table's object key, for a row alias.
-- Dynamic SQL on storage (diffs, notes of changed objects, conflicts) names
-- objects by this text (tgsis.object_key_sql says why the column's cast to
-- text will not do); TG100 for a key type not built into PostgreSQL
-- (tgsis.check_key_type).
CREATE FUNCTION tgsis.object_key_text_sql(p_t tgsis.versioned_tables, p_alias text)
RETURNS text
LANGUAGE plpgsql
STABLE
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_storage regclass := tgsis.storage_table(p_t.schemaname, p_t.tablename)::regclass;
BEGIN
    PERFORM tgsis.check_key_type(v_storage, p_t.objectkeyfield);
    RETURN tgsis.object_key_sql((SELECT a.atttypid FROM pg_catalog.pg_attribute a
                                  WHERE a.attrelid = v_storage AND a.attname = p_t.objectkeyfield AND NOT a.attisdropped),
                                format('%I.%I', p_alias, p_t.objectkeyfield));
END
$$;

COMMENT ON FUNCTION tgsis.object_key_text_sql(tgsis.versioned_tables, text) IS
    'SQL expression giving the canonical text (tgsis.object_key_sql) of the object key of a versioned table''s row p_alias';
