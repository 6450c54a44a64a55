-- tgsis.visible_object_keys(objectclass, keys, revisions): which of the keys name an object a revision set sees in any table of its class.
CREATE FUNCTION tgsis.visible_object_keys(p_objectclass text, p_keys text[], p_revisions integer[])
RETURNS text[]
LANGUAGE plpgsql
VOLATILE
AS $$
DECLARE
    v_t     record;
    v_found text[] := '{}';
    v_some  text[];
    v_key   text;
    v_row   tgsis.versioned_tables;
BEGIN
    FOR v_t IN
        SELECT t AS tbl, t.schemaname, t.tablename, t.objectkeyfield, format_type(a.atttypid, a.atttypmod) AS keytype,
               a.atttypid AS keytypid
          FROM tgsis.versioned_tables t
         CROSS JOIN LATERAL (SELECT tgsis.storage_table(t.schemaname, t.tablename)::regclass AS rel) s  -- once per table
          JOIN pg_catalog.pg_attribute a
            ON a.attrelid = s.rel AND a.attname = t.objectkeyfield
         WHERE t.objectclass = p_objectclass
    LOOP
        v_row := v_t.tbl;
        PERFORM tgsis.check_key_type(tgsis.storage_table(v_t.schemaname, v_t.tablename)::regclass, v_t.objectkeyfield);
        -- the keys cast to the column's type, so that the key index serves the lookup;
        -- a key that is no value of that type ('abc' for a bigint key) is a bad argument
        FOREACH v_key IN ARRAY coalesce(p_keys, '{}') LOOP
            BEGIN
                EXECUTE format('SELECT $1::%s', v_t.keytype) USING v_key;
            EXCEPTION WHEN data_exception THEN
                RAISE EXCEPTION 'object key % of class % is not a %', quote_nullable(v_key), quote_literal(p_objectclass), v_t.keytype
                    USING ERRCODE = 'TG100',
                          DETAIL = format('Column %I of %I.%I holds the keys of the class''s objects.',
                                          v_t.objectkeyfield, v_t.schemaname, v_t.tablename),
                          HINT = format('give keys that are %s values (for features: their ids)', v_t.keytype);
            END;
        END LOOP;
        -- read as the storage's owner from definer code (tgsis.storage_run)
        SELECT r INTO v_some FROM tgsis.storage_run(v_row, false, format(
            'SELECT coalesce(array_agg(DISTINCT %5$s), ''{}'') FROM %2$s v
              WHERE v.%1$I = ANY ($1::%4$s[]) AND v.revision = ANY ($2) AND NOT (v.lastrevs && $2)',
            v_t.objectkeyfield, tgsis.storage_table(v_t.schemaname, v_t.tablename), NULL, v_t.keytype,
            tgsis.object_key_sql(v_t.keytypid, format('v.%I', v_t.objectkeyfield))), p_keys, p_revisions) AS r;
        v_found := v_found || v_some;
    END LOOP;
    RETURN ARRAY(SELECT DISTINCT k FROM unnest(v_found) AS k ORDER BY k);
END
$$;

COMMENT ON FUNCTION tgsis.visible_object_keys(text, text[], integer[]) IS
    'the keys among p_keys of objects of a class that the revision set sees in at least one of the class''s tables';
