-- tgsis.write_object_rows(table, geoid, deleted, ids, floats, refs): write some rows of one object of a chunked model table, for the calling role.
-- The bulk edit of a model-1 object stored in chunks (docs/storage.md, "Writing
-- an edit"): check-in and save by difference, and the merges that write by
-- region (tgsis.db._state_write), give the ids that go (p_deleted) and the
-- rows that are new or changed (p_ids with their values: p_floats one row per
-- double precision column of tgsis.<table>, p_refs one row per vertex-id
-- column, each (columns x ids), in the row table's column order). Every touched
-- chunk is rewritten once, by the one writer of chunk contents
-- (tgsis.write_chunk_rows: closed and inserted anew in the working revision,
-- or in place when it is the working revision's), whatever the number of rows.
-- Roles other than the chunk table's owner may not update chunk versions (they
-- could rewrite other versions), and tgsis.write_chunk_rows is internal: so
-- this runs as tgsis's owner after the checks today's row path makes (the
-- set-based delete tgsis.close_object_rows, the storage's statement triggers):
-- INSERT (new or changed rows) and DELETE (rows that go, and rows changed: on
-- rows a change is a close and an insert) on the face
-- tgsis.<table> (42501), the class's write right on the object
-- (tgsis.check_class_write), the write right on the session's version and
-- TG301 while an older revision is viewed, TG305 for unversioned storage
-- outside DEFAULT's working revision, revision 0 for features of classes
-- without versioning (all three in tgsis.write_chunk_rows), the object not
-- locked by another version (TG303), and READ COMMITTED when rows of a
-- versioned table go or change (TG300, as tgsis.close_object_rows asks on rows;
-- an edit that only adds is written at any isolation level, as on rows). The object's write lock is taken
-- exclusively (tgsis.object_write_lock: no write through the face is in
-- flight on it; the version's checks and the lock are
-- tgsis.object_write_prepare, shared with chunk_rows_write), and the object is noted as changed in the working revision
-- when a chunk was written (tgsis.record_changed_objects; never for revision
-- 0). The rows go through a temporary table this function makes (owned by
-- tgsis's owner: one the session made itself under that name is refused,
-- 42501). Refused by name (TG100): a table not stored in chunks, arrays whose
-- shape does not match the columns, an id both deleted and written; and what
-- tgsis.write_chunk_rows refuses (NULL values, negative ids, a CHECK of the
-- row table). Returns the number of chunks written.
CREATE FUNCTION tgsis.write_object_rows(p_table text, p_geoid bigint, p_deleted bigint[], p_ids bigint[],
                                        p_floats double precision[] DEFAULT NULL, p_refs bigint[] DEFAULT NULL)
RETURNS bigint
LANGUAGE plpgsql
VOLATILE
SECURITY DEFINER
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_reg     tgsis.model_tables;
    v_face    text;
    v_tab     text;
    v_floats  text[];
    v_refs    text[];
    v_n       integer := coalesce(cardinality(p_ids), 0);
    v_d       integer := coalesce(cardinality(p_deleted), 0);
    v_keys    text[] := ARRAY[p_geoid::text];
    v_cols    text;
    v_vals    text;
    v_nulls   text;
    v_written bigint;
    v_stored  bigint;
    v_versioned boolean;
    v_held    text;
BEGIN
    SELECT * INTO v_reg FROM tgsis.model_tables t WHERE t.tablename = p_table AND t.chunkcolumn IS NOT NULL;
    IF NOT FOUND OR NOT tgsis.stored_in_chunks(p_table) THEN
        RAISE EXCEPTION 'tgsis.% is not stored in chunks', coalesce(quote_ident(p_table), 'NULL')
            USING ERRCODE = 'TG100',
                  DETAIL = 'tgsis.write_object_rows writes the model tables switched to chunks (tgsis.stored_in_chunks).',
                  HINT = 'write the rows of a table stored as rows through its view or storage';
    END IF;
    -- (a model table with columns of role 'value', a G-map dart's acellid and positive: this path's arrays do not
    -- carry them, which would be left NULL; nor a G-map's point, role 'point': a 2-D array per chunk)
    IF EXISTS (SELECT FROM tgsis.chunk_columns(p_table) c WHERE c.role IN ('value', 'point')) THEN
        RAISE EXCEPTION 'tgsis.% has columns tgsis.write_object_rows does not write: %', quote_ident(p_table),
                        (SELECT string_agg(c.name, ', ' ORDER BY c.colorder) FROM tgsis.chunk_columns(p_table) c WHERE c.role IN ('value', 'point'))
            USING ERRCODE = 'TG100',
                  HINT = format('write its rows through the face tgsis.%I or tgsis.insert_chunk_rows', p_table);
    END IF;
    v_face := format('tgsis.%I', p_table);
    v_floats := ARRAY(SELECT c.name FROM tgsis.chunk_columns(p_table) c WHERE c.role = 'float' ORDER BY c.colorder);
    v_refs := ARRAY(SELECT c.name FROM tgsis.chunk_columns(p_table) c WHERE c.role = 'ref' ORDER BY c.colorder);
    IF p_geoid IS NULL
       OR (SELECT count(*) FROM tgsis.chunk_columns(p_table) c WHERE c.role = 'key') <> 1
       OR (v_n > 0 AND cardinality(v_floats) > 0
           AND (array_ndims(p_floats) IS DISTINCT FROM 2 OR array_length(p_floats, 1) <> cardinality(v_floats)
                OR array_length(p_floats, 2) <> v_n))
       OR (v_n > 0 AND cardinality(v_refs) > 0
           AND (array_ndims(p_refs) IS DISTINCT FROM 2 OR array_length(p_refs, 1) <> cardinality(v_refs)
                OR array_length(p_refs, 2) <> v_n))
       OR (v_n > 0 AND cardinality(v_floats) = 0 AND coalesce(cardinality(p_floats), 0) > 0)
       OR (v_n > 0 AND cardinality(v_refs) = 0 AND coalesce(cardinality(p_refs), 0) > 0) THEN
        RAISE EXCEPTION 'the rows to write into tgsis.% do not match its columns', quote_ident(p_table)
            USING ERRCODE = 'TG100',
                  DETAIL = format('geoid %s; %s ids; floats %s for the columns (%s), refs %s for the columns (%s).',
                                  coalesce(p_geoid::text, 'NULL'), v_n,
                                  coalesce(array_dims(p_floats), 'NULL'), array_to_string(v_floats, ', '),
                                  coalesce(array_dims(p_refs), 'NULL'), array_to_string(v_refs, ', ')),
                  HINT = 'give one row of values per column, as long as the ids';
    END IF;
    IF v_n + v_d = 0 THEN
        RETURN 0;
    END IF;
    IF EXISTS (SELECT FROM unnest(p_deleted) AS d WHERE d = ANY (p_ids)) THEN
        RAISE EXCEPTION 'cannot write these rows into tgsis.%: an id is both deleted and written', quote_ident(p_table)
            USING ERRCODE = 'TG100',
                  DETAIL = 'A written row replaces the row of its id: its id is not also deleted.',
                  HINT = 'give each key once, with all its values';
    END IF;
    -- "a written id the object holds now" (read below only when needed, as the face would answer it: the visible
    -- chunk versions, those of the session's set when versioned, every one when not; tgsis's owner passes the class
    -- rights filter) but read by key: only the chunks holding p_ids are decoded (tgsis.storage_row_versions),
    -- where the face decoded the whole object
    v_held := format('SELECT (array_agg(f.%2$I))[1] FROM %1$s f WHERE f.%3$I = $1 AND f.%2$I = ANY ($2)'
                     ' AND (NOT $3 OR (%4$s))',
                     tgsis.storage_row_versions('tgsis', p_table, p_ids), v_reg.chunkcolumn, v_reg.keycolumn,
                     tgsis.visible_versions('f', '(SELECT tgsis.get_revisions(true))::integer[]'));
    v_versioned := EXISTS (SELECT FROM tgsis.versioned_tables t WHERE t.schemaname = 'tgsis' AND t.tablename = p_table);
    -- the rights of today's row path: the view's privileges, the class's right on the object
    IF (v_n > 0 AND NOT has_table_privilege(tgsis.calling_role(), v_face::regclass, 'INSERT'))
       OR (v_d > 0 AND NOT has_table_privilege(tgsis.calling_role(), v_face::regclass, 'DELETE')) THEN
        RAISE EXCEPTION 'role % may not write %', quote_ident(tgsis.calling_role()), v_face
            USING ERRCODE = 'insufficient_privilege',
                  DETAIL = 'New and changed rows need INSERT on it, rows that go DELETE.',
                  HINT = 'its owner can GRANT INSERT, DELETE on it';
    END IF;
    -- a written id that the object holds now is a change: on rows a close and an insert (tgsis.close_object_rows
    -- asks DELETE), so a role without DELETE may add rows, not rewrite stored ones (read only when it lacks DELETE)
    IF v_n > 0 AND NOT has_table_privilege(tgsis.calling_role(), v_face::regclass, 'DELETE') THEN
        EXECUTE v_held INTO v_stored USING p_geoid, p_ids, v_versioned;
        IF v_stored IS NOT NULL THEN
            RAISE EXCEPTION 'role % may not write %', quote_ident(tgsis.calling_role()), v_face
                USING ERRCODE = 'insufficient_privilege',
                      DETAIL = format('Id %s of object %s is stored: changing a row needs DELETE on it, as on rows.',
                                      v_stored, p_geoid),
                      HINT = 'its owner can GRANT INSERT, DELETE on it';
        END IF;
    END IF;
    PERFORM tgsis.check_class_write(ARRAY[p_geoid], 'UPDATE');
    IF EXISTS (SELECT FROM tgsis.versioned_tables t WHERE t.schemaname = 'tgsis' AND t.tablename = p_table) THEN
        -- rows that go or change are closed on rows (tgsis.close_object_rows), which needs READ COMMITTED: the
        -- same refusal here (TG300), an edit that only adds is written at any level as on rows (read only then)
        IF current_setting('transaction_isolation') <> 'read committed' THEN
            IF v_d = 0 AND v_n > 0 THEN
                EXECUTE v_held INTO v_stored USING p_geoid, p_ids, v_versioned;
            END IF;
            IF v_d > 0 OR v_stored IS NOT NULL THEN
                PERFORM tgsis.require_read_committed('a set-based delete of versioned objects');
            END IF;
        END IF;
    END IF;
    PERFORM tgsis.object_write_prepare(p_table, v_reg.objectclass, v_keys);  -- TG301, TG303 or TG305; the locks

    -- the rows, in a temporary table of tgsis's owner (the writer reads it in several statements)
    v_tab := format('pg_temp.%I', 'tgsis_object_rows_' || p_table);
    IF to_regclass(v_tab) IS NULL THEN
        EXECUTE format('CREATE TEMP TABLE %s AS SELECT *, false AS _delete FROM %s WITH NO DATA',
                       v_tab, tgsis.row_shape(p_table));
    ELSIF (SELECT c.relowner FROM pg_class c WHERE c.oid = to_regclass(v_tab))
          <> (SELECT r.oid FROM pg_roles r WHERE r.rolname = current_user) THEN
        RAISE EXCEPTION 'the session''s table % was not made by tgsis.write_object_rows', v_tab
            USING ERRCODE = 'insufficient_privilege', HINT = 'drop the temporary table and write again';
    ELSE
        EXECUTE format('TRUNCATE %s', v_tab);
    END IF;
    v_cols := array_to_string(ARRAY[quote_ident(v_reg.keycolumn), quote_ident(v_reg.chunkcolumn)]
                              || ARRAY(SELECT quote_ident(c) FROM unnest(v_floats || v_refs) AS c), ', ');
    v_nulls := array_to_string(ARRAY(SELECT 'NULL' FROM unnest(v_floats || v_refs) AS c), ', ');
    IF v_d > 0 THEN
        EXECUTE format('INSERT INTO %s (%s, _delete) SELECT $1, d%s, true FROM unnest($2) AS d',
                       v_tab, v_cols, CASE WHEN v_nulls <> '' THEN ', ' || v_nulls ELSE '' END)
          USING p_geoid, p_deleted;
    END IF;
    IF v_n > 0 THEN
        -- each column a slice of the (columns x ids) arrays, unnested side by side with the ids
        v_vals := array_to_string(ARRAY(SELECT format('$3[%s:%s][:]', o, o) FROM generate_series(1, cardinality(v_floats)) AS o)
                                  || ARRAY(SELECT format('$4[%s:%s][:]', o, o) FROM generate_series(1, cardinality(v_refs)) AS o), ', ');
        EXECUTE format('INSERT INTO %s (%s, _delete) SELECT $1, u.* , false FROM unnest($2%s) AS u',
                       v_tab, v_cols, CASE WHEN v_vals <> '' THEN ', ' || v_vals ELSE '' END)
          USING p_geoid, p_ids, p_floats, p_refs;
    END IF;
    v_written := tgsis.write_chunk_rows(p_table, v_tab::regclass);
    EXECUTE format('TRUNCATE %s', v_tab);
    IF v_written > 0 AND EXISTS (SELECT FROM tgsis.versioned_tables t WHERE t.schemaname = 'tgsis' AND t.tablename = p_table)
       AND NOT (v_reg.objectclass = 'feature' AND EXISTS (SELECT FROM tgsis.unversioned_features u WHERE u.geoid = p_geoid)) THEN
        PERFORM tgsis.record_changed_objects('tgsis', p_table, v_keys);
    END IF;
    RETURN v_written;
END
$$;

COMMENT ON FUNCTION tgsis.write_object_rows(text, bigint, bigint[], bigint[], double precision[], bigint[]) IS
    'write some rows of one object of a model table stored in chunks for the calling role (INSERT/DELETE on the face, the class''s write right, the version''s, object locks): ids deleted, ids written with their values as (columns x ids) arrays; every touched chunk rewritten once by tgsis.write_chunk_rows; the object noted as changed; returns the chunks written';
