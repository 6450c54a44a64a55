-- tgsis.canonical_object_keys(objectclass, keys): object keys given as text by a user, in their canonical text.
-- Keys a user passes (tgsis.lock_objects, unlock_objects, resolve_conflict,
-- conflict_rows, the client's arguments) are read as values of the key
-- column's type with the session's settings, as any literal of that type
-- ('02/01/2024' is 2 January under DateStyle DMY), and given back in the
-- text tgsis stores and compares (tgsis.object_key_text), so that a key names
-- the same object whatever the settings of the session that wrote its
-- locks, notes and conflicts. A class whose tables are keyed by several
-- types must read each key the same way in all of them (TG100 otherwise);
-- keys of a class with no table are kept as given. A key that is no value
-- of the type fails with TG100.
CREATE FUNCTION tgsis.canonical_object_keys(p_objectclass text, p_keys text[])
RETURNS text[]
LANGUAGE plpgsql
STABLE
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_t      record;
    v_result text[];
    v_some   text[];
    v_key    text;
    v_i      integer;
BEGIN
    IF p_keys IS NULL THEN
        RETURN NULL;
    END IF;
    FOR v_t IN
        SELECT DISTINCT ON (a.atttypid) t.schemaname, t.tablename, t.objectkeyfield, a.atttypid AS keytype,
               s.rel AS storage
          FROM tgsis.versioned_tables t
         CROSS JOIN LATERAL (SELECT tgsis.storage_table(t.schemaname, t.tablename)::regclass AS rel) s  -- once per table
          JOIN pg_catalog.pg_attribute a
            ON a.attrelid = s.rel
           AND a.attname = t.objectkeyfield AND NOT a.attisdropped
         WHERE t.objectclass = p_objectclass
         ORDER BY a.atttypid, t.schemaname, t.tablename
    LOOP
        -- only built-in types' input and output functions run here (TG100 otherwise)
        PERFORM tgsis.check_key_type(v_t.storage, v_t.objectkeyfield);
        v_some := '{}';
        FOREACH v_key IN ARRAY p_keys LOOP
            BEGIN
                EXECUTE format('SELECT %s FROM (SELECT $1::%s AS k) AS s',
                               tgsis.object_key_sql(v_t.keytype, 's.k'), v_t.keytype::regtype)
                   INTO STRICT v_key USING v_key;
            EXCEPTION WHEN data_exception THEN
                RAISE EXCEPTION 'object key % of class % is not a %', quote_nullable(v_key), quote_literal(p_objectclass),
                        format_type(v_t.keytype, NULL)
                    USING ERRCODE = 'TG100',
                          DETAIL = format('Column %I of %I.%I holds the keys of the class''s objects.',
                                          v_t.objectkeyfield, v_t.schemaname, v_t.tablename),
                          HINT = format('give keys that are %s values (for features: their ids)', format_type(v_t.keytype, NULL));
            END;
            v_some := v_some || v_key;
        END LOOP;
        IF v_result IS NULL THEN
            v_result := v_some;
        ELSE
            FOR v_i IN 1 .. cardinality(p_keys) LOOP
                IF v_result[v_i] IS DISTINCT FROM v_some[v_i] THEN
                    RAISE EXCEPTION 'object key % of class % names different objects in the class''s tables (% and %)',
                            quote_nullable(p_keys[v_i]), quote_literal(p_objectclass), quote_nullable(v_result[v_i]),
                            quote_nullable(v_some[v_i])
                        USING ERRCODE = 'TG100',
                              DETAIL = 'The tables of the class are keyed by columns of different types, which read the key differently.',
                              HINT = 'give the key in the form both types read alike';
                END IF;
            END LOOP;
        END IF;
    END LOOP;
    RETURN coalesce(v_result, p_keys);
END
$$;

COMMENT ON FUNCTION tgsis.canonical_object_keys(text, text[]) IS
    'object keys of a class given as text, read in the key column''s type with the session''s settings and given back as canonical text (tgsis.object_key_text); TG100 for a key that is no value of the type';
