-- tgsis.delete_chunk_rows(table, columns, ints, floats): delete rows of a model table stored in chunks by their keys, for the calling role, set-based.
-- The bulk delete beside tgsis.insert_chunk_rows: the model-2 and model-3
-- check-in and merges by difference (src/tgsis/db/_state_write.py) delete the
-- rows whose key is gone or whose values changed, which through the face is a
-- chunk rewrite per row (tgsis.chunk_face_write). Here the keys (p_ints one row
-- per bigint key column, p_floats one per double precision key column, each
-- (columns x rows); p_columns names them, the bigint ones first: together
-- exactly the row table's primary key, tgsis.chunk_key and the chunk column)
-- go in one call of the one writer of chunk contents
-- (tgsis.write_chunk_rows, rows with _delete true: each touched chunk written
-- once, emptied ones deleted or closed) after the checks of a DELETE through
-- the face for the whole set: DELETE on the face (42501), the class's right to
-- delete the features' rows (tgsis.check_class_write 'UPDATE, DELETE'), the
-- version's write right and TG301 while an older revision is viewed, TG305 for
-- unversioned storage outside DEFAULT's working revision, revision 0 for the
-- features of classes without versioning, the objects not locked by another
-- version (TG303); 40001 for a snapshot older than the chunk table
-- (tgsis.chunk_snapshot_guard). The objects' write locks are taken
-- exclusively first (tgsis.object_write_lock: no face writer of them in
-- flight). A key that is not visible is skipped, as a DELETE skips it. The
-- objects are noted as changed in the working revision. Runs as tgsis's owner
-- (roles may not update chunk versions) with the keys in a temporary table of
-- its own (42501 for one the session made under that name). Refused by name
-- (TG100): a table not stored in chunks, columns that are not its key, arrays
-- of another shape, a NULL key, a key twice. Returns the number of rows
-- deleted (the visible keys among those given).
CREATE FUNCTION tgsis.delete_chunk_rows(p_table text, p_columns text[], p_ints bigint[], p_floats double precision[])
RETURNS bigint
LANGUAGE plpgsql
VOLATILE
SECURITY DEFINER
SET search_path = pg_catalog, pg_temp
SET extra_float_digits = 1  -- (as tgsis.insert_chunk_rows: keys never printed short)
AS $$
DECLARE
    v_reg       tgsis.model_tables;
    v_face      regclass;
    v_tab       text;
    v_key       text[];
    v_icols     text[];
    v_fcols     text[];
    v_n         integer;
    v_geoids    bigint[];
    v_keys      text[];
    v_ids       bigint[];
    v_vals      text;
    v_versioned boolean;
    v_found     bigint;
BEGIN
    SELECT * INTO v_reg FROM tgsis.model_tables t WHERE t.tablename = p_table AND t.chunkcolumn IS NOT NULL;
    IF NOT FOUND OR NOT tgsis.stored_in_chunks(p_table) THEN
        RAISE EXCEPTION 'tgsis.% is not stored in chunks', coalesce(quote_ident(p_table), 'NULL')
            USING ERRCODE = 'TG100',
                  DETAIL = 'tgsis.delete_chunk_rows deletes from the model tables switched to chunks (tgsis.stored_in_chunks).',
                  HINT = 'delete the rows of a table stored as rows through its view';
    END IF;
    -- a snapshot older than the chunk table (and the catalog rows read below) is 40001, as the face's check
    PERFORM tgsis.chunk_snapshot_guard(to_regclass(format('tgsis.%I', p_table || '_chunk')));
    v_face := format('tgsis.%I', p_table)::regclass;
    v_key := tgsis.chunk_key(p_table) || v_reg.chunkcolumn;
    v_icols := ARRAY(SELECT c.name FROM tgsis.chunk_columns(p_table) c
                      WHERE c.name = ANY (v_key) AND c.typename = 'bigint' ORDER BY c.colorder);
    v_fcols := ARRAY(SELECT c.name FROM tgsis.chunk_columns(p_table) c
                      WHERE c.name = ANY (v_key) AND c.typename = 'double precision' ORDER BY c.colorder);
    v_n := coalesce(array_length(p_ints, 2), 0);
    IF p_columns IS NULL OR cardinality(v_icols || v_fcols) <> cardinality(v_key)
       OR cardinality(p_columns) <> cardinality(v_key)
       OR (SELECT array_agg(c ORDER BY c) FROM unnest(p_columns[1:cardinality(v_icols)]) AS c)
          IS DISTINCT FROM (SELECT array_agg(c ORDER BY c) FROM unnest(v_icols) AS c)
       OR (SELECT coalesce(array_agg(c ORDER BY c), '{}') FROM unnest(p_columns[cardinality(v_icols) + 1:]) AS c)
          IS DISTINCT FROM (SELECT coalesce(array_agg(c ORDER BY c), '{}') FROM unnest(v_fcols) AS c)
       OR array_ndims(p_ints) IS DISTINCT FROM 2 OR array_length(p_ints, 1) <> cardinality(v_icols)
       OR (cardinality(v_fcols) > 0 AND (array_ndims(p_floats) IS DISTINCT FROM 2
                                         OR array_length(p_floats, 1) <> cardinality(v_fcols)
                                         OR array_length(p_floats, 2) <> v_n))
       OR (cardinality(v_fcols) = 0 AND coalesce(cardinality(p_floats), 0) > 0) THEN
        RAISE EXCEPTION 'the keys to delete from tgsis.% do not match its key', quote_ident(p_table)
            USING ERRCODE = 'TG100',
                  DETAIL = format('columns %s; ints %s for the bigint key columns (%s), floats %s for the double precision ones (%s).',
                                  coalesce(p_columns::text, 'NULL'), coalesce(array_dims(p_ints), 'NULL'),
                                  array_to_string(v_icols, ', '), coalesce(array_dims(p_floats), 'NULL'),
                                  array_to_string(v_fcols, ', ')),
                  HINT = 'name every key column once, the bigint ones first, and give one row of values per column, as long as the keys';
    END IF;
    IF v_n = 0 THEN
        RETURN 0;
    END IF;
    v_geoids := ARRAY(SELECT DISTINCT g FROM unnest(p_ints[array_position(p_columns, v_reg.keycolumn):array_position(p_columns, v_reg.keycolumn)][:]) AS g
                       WHERE g IS NOT NULL ORDER BY g);
    v_keys := v_geoids::text[];
    IF NOT has_table_privilege(tgsis.calling_role(), v_face, 'DELETE') THEN
        RAISE EXCEPTION 'permission denied for view %', p_table
            USING ERRCODE = 'insufficient_privilege', DETAIL = format('Deleting rows of %s needs DELETE on it.', v_face),
                  HINT = 'its owner can GRANT DELETE on it';
    END IF;
    PERFORM tgsis.check_class_write(v_geoids, 'UPDATE, DELETE');
    v_versioned := EXISTS (SELECT FROM tgsis.versioned_tables t WHERE t.schemaname = 'tgsis' AND t.tablename = p_table);
    IF v_versioned THEN
        PERFORM tgsis.write_revision();  -- TG002, TG301 before any lock is taken
        PERFORM tgsis.check_objects_unlocked(v_reg.objectclass, v_keys);
    ELSE
        PERFORM tgsis.plain_write_check('tgsis', p_table);  -- TG305
    END IF;
    PERFORM tgsis.object_write_lock(v_reg.objectclass, v_keys);

    -- the keys, in a temporary table of tgsis's owner (the writer reads it in several statements)
    v_tab := format('pg_temp.%I', 'tgsis_delete_rows_' || p_table);
    IF to_regclass(v_tab) IS NULL THEN
        EXECUTE format('CREATE TEMP TABLE %s AS SELECT *, false AS _delete FROM %s WITH NO DATA',
                       v_tab, tgsis.row_shape(p_table));
    ELSIF (SELECT c.relowner FROM pg_class c WHERE c.oid = to_regclass(v_tab))
          <> (SELECT r.oid FROM pg_roles r WHERE r.rolname = current_user) THEN
        RAISE EXCEPTION 'the session''s table % was not made by tgsis.delete_chunk_rows', v_tab
            USING ERRCODE = 'insufficient_privilege', HINT = 'drop the temporary table and write again';
    ELSE
        EXECUTE format('TRUNCATE %s', v_tab);
    END IF;
    v_vals := array_to_string(ARRAY(SELECT format('$1[%s:%s][:]', o, o) FROM generate_series(1, cardinality(v_icols)) AS o)
                              || ARRAY(SELECT format('$2[%s:%s][:]', o, o) FROM generate_series(1, cardinality(v_fcols)) AS o), ', ');
    EXECUTE format('INSERT INTO %s (%s, _delete) SELECT u.*, true FROM unnest(%s) AS u',
                   v_tab, array_to_string(ARRAY(SELECT quote_ident(c) FROM unnest(p_columns) AS c), ', '), v_vals)
      USING p_ints, p_floats;
    -- the visible keys among them (read after the objects' write locks; only the chunks holding their ids decoded):
    -- what a DELETE would count; the others are skipped
    v_ids := ARRAY(SELECT DISTINCT i FROM unnest(p_ints[array_position(p_columns, v_reg.chunkcolumn):array_position(p_columns, v_reg.chunkcolumn)][:]) AS i
                     WHERE i IS NOT NULL);
    EXECUTE format('SELECT count(*) FROM %s r WHERE EXISTS (SELECT FROM %s f WHERE %s'
                   ' AND (NOT $1 OR ((f.revision = ANY ((SELECT tgsis.get_revisions(true))::integer[])) IS TRUE'
                   ' AND (NOT f.revclosed OR NOT (f.lastrevs && (SELECT tgsis.get_revisions(true)))))))',
                   v_tab, tgsis.storage_row_versions('tgsis', p_table, v_ids),
                   (SELECT string_agg(format('f.%I = r.%I', k, k), ' AND ') FROM unnest(v_key) AS k))
       INTO v_found USING v_versioned;
    IF v_found > 0 THEN
        PERFORM tgsis.write_chunk_rows(p_table, v_tab::regclass);  -- TG100: a NULL key, a key twice
    END IF;
    EXECUTE format('TRUNCATE %s', v_tab);
    IF v_found > 0 AND v_versioned THEN
        v_keys := ARRAY(SELECT k FROM unnest(v_keys) AS k
                         WHERE NOT (v_reg.objectclass = 'feature'
                                    AND EXISTS (SELECT FROM tgsis.unversioned_features u WHERE u.geoid = k::bigint)));
        IF cardinality(v_keys) > 0 THEN
            PERFORM tgsis.record_changed_objects('tgsis', p_table, v_keys);
        END IF;
    END IF;
    RETURN v_found;
END
$$;

REVOKE ALL ON FUNCTION tgsis.delete_chunk_rows(text, text[], bigint[], double precision[]) FROM PUBLIC;
GRANT EXECUTE ON FUNCTION tgsis.delete_chunk_rows(text, text[], bigint[], double precision[]) TO tgsis_reader;

COMMENT ON FUNCTION tgsis.delete_chunk_rows(text, text[], bigint[], double precision[]) IS
    'delete rows of a model table stored in chunks by their keys for the calling role, set-based (DELETE on the face, the class''s right, the version''s, object locks, the objects'' write locks): the bigint key columns then the double precision ones named, their values as (columns x keys) arrays; keys not visible skipped; every touched chunk written once by tgsis.write_chunk_rows; the objects noted as changed; returns the rows deleted';
