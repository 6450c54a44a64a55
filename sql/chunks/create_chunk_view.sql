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
-- which gets the view's SELECT grants. Not idempotent: TG201 when it exists.
CREATE FUNCTION tgsis.create_chunk_view(p_table text)
RETURNS regclass
LANGUAGE plpgsql
VOLATILE
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_reg    tgsis.model_tables;
    v_chunk  regclass;
    v_view   text := p_table || '_chunk_rows';
    v_shift  integer;
    v_refs   text[];
    v_first  text;
    v_select text[] := '{}';
    v_arrays text[] := '{}';
    v_alias  text[] := '{}';
    v_c      record;
    v_acl    record;
BEGIN
    SELECT * INTO v_reg FROM tgsis.model_tables t WHERE t.tablename = p_table;
    PERFORM FROM tgsis.chunk_columns(p_table);  -- TG200 / TG100
    v_chunk := to_regclass(format('tgsis.%I', p_table || '_chunk'));
    IF v_chunk IS NULL THEN
        RAISE EXCEPTION 'tgsis.% has no chunk table', quote_ident(p_table)
            USING ERRCODE = 'TG200', HINT = 'create the chunk table first';
    END IF;
    IF to_regclass(format('tgsis.%I', v_view)) IS NOT NULL THEN
        RAISE EXCEPTION 'tgsis.% exists already', quote_ident(v_view) USING ERRCODE = 'TG201';
    END IF;
    v_shift := round(log(2, v_reg.chunksize))::integer;
    v_refs := ARRAY(SELECT c.name FROM tgsis.chunk_columns(p_table) c WHERE c.role = 'ref' ORDER BY c.colorder);
    FOR v_c IN SELECT c.name, c.role FROM tgsis.chunk_columns(p_table) c ORDER BY c.colorder LOOP
        IF v_c.role = 'key' THEN
            v_select := v_select || format('c.%I', v_c.name);
        ELSIF v_c.role = 'chunk' THEN
            v_select := v_select || format('(c.chunk << %s) + (u.o - 1) AS %I', v_shift, v_c.name);  -- (u.o - 1) first: id 2^63 - 1 is slot 1024
        ELSIF v_c.role = 'float' THEN
            v_arrays := v_arrays || format('c.%I', v_c.name);
            v_alias := v_alias || quote_ident(v_c.name);
            v_select := v_select || format('u.%I', v_c.name);
            v_first := coalesce(v_first, format('u.%I IS NOT NULL', v_c.name));
        ELSE
            v_arrays := v_arrays || format('c.%I', v_c.name) || format('c.%I', v_c.name || '_wide');
            v_alias := v_alias || quote_ident(v_c.name) || quote_ident(v_c.name || '_wide');
            -- the first ref relative to vbase, the others to the first
            v_select := v_select || format('CASE WHEN c.vbase IS NOT NULL THEN c.vbase + %s ELSE u.%I END AS %I',
                                           CASE WHEN v_c.name = v_refs[1] THEN format('u.%I', v_c.name)
                                                ELSE format('u.%I + u.%I', v_refs[1], v_c.name) END,
                                           v_c.name || '_wide', v_c.name);
            v_first := coalesce(v_first, format('(u.%I IS NOT NULL OR u.%I IS NOT NULL)', v_c.name, v_c.name || '_wide'));
        END IF;
    END LOOP;
    EXECUTE format('CREATE VIEW tgsis.%I WITH (security_invoker = true) AS SELECT %s, c.revision, c.lastrevs, c.revclosed '
                   'FROM %s c CROSS JOIN LATERAL unnest(%s) WITH ORDINALITY AS u(%s, o) WHERE %s',
                   v_view, array_to_string(v_select, ', '), v_chunk, array_to_string(v_arrays, ', '),
                   array_to_string(v_alias, ', '), v_first);
    EXECUTE format('COMMENT ON VIEW tgsis.%I IS %L', v_view,
                   format('the chunks of %s decoded: one row per present slot and chunk version, with the columns of tgsis.%s '
                          'and the chunk version''s revision, lastrevs, revclosed (no visibility filter)', v_chunk, p_table));
    FOR v_c IN SELECT a.attname, a.attnum FROM pg_attribute a
                WHERE a.attrelid = format('tgsis.%I', v_view)::regclass AND a.attnum > 0 ORDER BY a.attnum LOOP
        EXECUTE format('COMMENT ON COLUMN tgsis.%I.%I IS %L', v_view, v_c.attname,
                       coalesce(col_description(tgsis.storage_table('tgsis', p_table)::regclass,
                                                (SELECT a.attnum FROM pg_attribute a
                                                  WHERE a.attrelid = tgsis.storage_table('tgsis', p_table)::regclass
                                                    AND a.attname = v_c.attname)::integer),
                                format('%s of the chunk version', v_c.attname)));
    END LOOP;
    FOR v_acl IN SELECT DISTINCT a.grantee FROM pg_class c, aclexplode(c.relacl) AS a
                  WHERE c.oid = v_chunk AND a.grantee <> c.relowner AND a.privilege_type = 'SELECT' LOOP
        EXECUTE format('GRANT SELECT ON tgsis.%I TO %s', v_view,
                       CASE WHEN v_acl.grantee = 0 THEN 'PUBLIC' ELSE quote_ident(pg_get_userbyid(v_acl.grantee)) END);
    END LOOP;
    RETURN format('tgsis.%I', v_view)::regclass;
END
$$;

REVOKE ALL ON FUNCTION tgsis.create_chunk_view(text) FROM PUBLIC;

COMMENT ON FUNCTION tgsis.create_chunk_view(text) IS
    'create tgsis.<table>_chunk_rows: the rows of tgsis.<table>_chunk decoded (one per present slot and chunk version: the row table''s columns, then revision, lastrevs, revclosed), security_invoker, with the chunk table''s SELECT grants; no visibility filter; TG200 without a chunk table, TG201 when it exists';
