-- tgsis.create_chunk_view(table): create tgsis.<table>_chunk_rows, the rows of tgsis.<table>_chunk decoded.
-- One row per present slot of every chunk version, with the row table's
-- columns in its order (the local id = chunk * chunksize + slot - 1; vertex
-- ids decoded from vbase and the differences, or from the _wide columns) and
-- the chunk version's revision, lastrevs and revclosed: the versioned face
-- of the next step puts today's visibility test on top of it (docs/storage.md,
-- "The relational face"), the tests read chunk contents through it. A filter
-- on the key (geoid) reaches the chunk table's primary key: a scan of one
-- object reads only its chunks. security_invoker: a role reads through it
-- what it may read of the chunk table (its grants, its row-level security),
-- which gets the view's SELECT grants. A snapshot older than the chunk
-- table's file (tgsis.chunk_snapshot_guard, once per query) gets 40001, not an
-- empty set. Not idempotent: TG201 when it exists.
CREATE FUNCTION tgsis.create_chunk_view(p_table text)
RETURNS regclass
LANGUAGE plpgsql
VOLATILE
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_chunk  regclass;
    v_view   text := tgsis.chunk_relation(p_table, '_chunk_rows');
    v_dec    record;
    v_c      record;
    v_acl    record;
BEGIN
    v_chunk := tgsis.chunk_table_of(p_table);  -- TG200 / TG100
    IF to_regclass(v_view) IS NOT NULL THEN
        RAISE EXCEPTION '% exists already', v_view USING ERRCODE = 'TG201';
    END IF;
    SELECT * INTO v_dec FROM tgsis.chunk_decode_sql(p_table, 'c') AS d;
    EXECUTE format('CREATE VIEW %s WITH (security_invoker = true) AS SELECT %s, c.revision, c.lastrevs, c.revclosed '
                   'FROM %s c%s CROSS JOIN LATERAL unnest(%s) WITH ORDINALITY AS u(%s, o) '
                   'WHERE (SELECT tgsis.chunk_snapshot_guard(%L::regclass)) AND %s',
                   v_view, v_dec.select_list, v_chunk, v_dec.joins, v_dec.arrays, v_dec.aliases, v_chunk::text, v_dec.present);
    EXECUTE format('COMMENT ON VIEW %s IS %L', v_view,
                   format('the chunks of %s decoded: one row per present slot and chunk version, with the columns of %s '
                          'and the chunk version''s revision, lastrevs, revclosed (no visibility filter)', v_chunk,
                          tgsis.chunk_relation(p_table, '')));
    FOR v_c IN SELECT a.attname, a.attnum FROM pg_attribute a
                WHERE a.attrelid = v_view::regclass AND a.attnum > 0 ORDER BY a.attnum LOOP
        -- revision, lastrevs, revclosed: the chunk table's (a versioned row storage has its own, of row versions)
        EXECUTE format('COMMENT ON COLUMN %s.%I IS %L', v_view, v_c.attname,
                       coalesce(CASE WHEN v_c.attname IN ('revision', 'lastrevs', 'revclosed')
                                     THEN col_description(v_chunk, (SELECT a.attnum FROM pg_attribute a
                                                                     WHERE a.attrelid = v_chunk AND a.attname = v_c.attname)::integer)
                                END,
                                col_description(tgsis.row_shape(p_table),
                                                (SELECT a.attnum FROM pg_attribute a
                                                  WHERE a.attrelid = tgsis.row_shape(p_table)
                                                    AND a.attname = v_c.attname)::integer),
                                format('%s of the chunk version', v_c.attname)));
    END LOOP;
    FOR v_acl IN SELECT DISTINCT a.grantee FROM pg_class c, aclexplode(c.relacl) AS a
                  WHERE c.oid = v_chunk AND a.grantee <> c.relowner AND a.privilege_type = 'SELECT' LOOP
        EXECUTE format('GRANT SELECT ON %s TO %s', v_view,
                       CASE WHEN v_acl.grantee = 0 THEN 'PUBLIC' ELSE quote_ident(pg_get_userbyid(v_acl.grantee)) END);
    END LOOP;
    RETURN v_view::regclass;
END
$$;

REVOKE ALL ON FUNCTION tgsis.create_chunk_view(text) FROM PUBLIC;

COMMENT ON FUNCTION tgsis.create_chunk_view(text) IS
    'create tgsis.<table>_chunk_rows: the rows of tgsis.<table>_chunk decoded (one per present slot and chunk version: the row table''s columns, then revision, lastrevs, revclosed), security_invoker, with the chunk table''s SELECT grants; no visibility filter; TG200 without a chunk table, TG201 when it exists';
