-- tgsis.chunk_rows_write(caller, table, delete columns, delete ints, delete floats, columns, ints, floats, bools): the set-based writer of tgsis.delete_chunk_rows, insert_chunk_rows and replace_chunk_rows.
-- Internal: the three SECURITY DEFINER entry points call it with p_caller
-- 'delete', 'insert' or 'replace' (their messages name the caller, as each
-- did alone). It makes, in this order, the checks of a DELETE through the
-- face for the keys (p_delete_*: p_delete_columns names the key columns, the
-- bigint ones first, p_delete_ints and p_delete_floats their values, each
-- (columns x keys)) and those of an INSERT for the rows (p_columns: the
-- bigint, integer or smallint columns, the double precision ones, then the
-- boolean ones; p_ints, p_floats, p_bools their values, each
-- (columns x rows); a column that may be NULL may be left out; a point, a
-- G-map's vertex of m coordinates, is named m times in a row among the
-- double precision ones, one row of p_floats per coordinate):
--   TG100 for a table not stored in chunks; 40001 for a snapshot older than
--   the chunk table (tgsis.chunk_snapshot_guard; with keys to delete, as
--   delete_chunk_rows did); TG100 for keys or rows of another shape; DELETE
--   on the face for keys (42501), INSERT for rows (42501); the class's right
--   (tgsis.check_class_write: 'UPDATE, DELETE' for the keys' objects, 'UPDATE'
--   for the rows'); the version's write right and TG301 while an older
--   revision is viewed (tgsis.write_revision) and the objects not locked by
--   another version (TG303), or TG305 for unversioned storage outside
--   DEFAULT's working revision; then the objects' write locks, exclusively
--   (tgsis.object_write_lock: no face writer of them in flight). These last
--   three steps are tgsis.object_write_prepare, shared with write_object_rows.
-- The keys and rows go into a temporary table of tgsis's owner (42501 for one
-- the session made under that name): the keys as rows with _delete true,
-- the rows with _delete false. Keys not visible are skipped (as a DELETE
-- skips them; none visible: no key is written); a row whose key is visible
-- and not among the keys deleted is 23505 naming <table>_pkey, as the rows'
-- primary key (an insert never replaces a row unless its key is deleted by
-- the same call). A key deleted and written again by one call is written
-- once (the row replaces the deletion), so every touched chunk is written
-- once by one call of tgsis.write_chunk_rows: one chunk version, where a
-- delete_chunk_rows then an insert_chunk_rows wrote two (the first dead at
-- once). Only a key deleted and written again with other bits (-0.0 and 0.0,
-- equal by float8 =) goes in two passes, the deletes first, as those two
-- calls did (the chunk keeps one key for all its slots). What
-- tgsis.write_chunk_rows refuses (TG100: NULL values, negative ids, a key
-- twice, a key of other bits than its chunk's; 23514 a CHECK) is refused. The
-- objects are noted as changed in the working revision (those whose keys
-- were deleted when one was visible, those of the rows when a chunk was
-- written). Returns the rows deleted (the visible keys among those given)
-- and the chunks written.
CREATE FUNCTION tgsis.chunk_rows_write(p_caller text, p_table text,
                                       p_delete_columns text[], p_delete_ints bigint[], p_delete_floats double precision[],
                                       p_columns text[], p_ints bigint[], p_floats double precision[], p_bools boolean[],
                                       OUT rows_deleted bigint, OUT chunks_written bigint)
LANGUAGE plpgsql
VOLATILE
SET search_path = pg_catalog, pg_temp
SET extra_float_digits = 1  -- keys compared and printed as text below: exactly
AS $$
DECLARE
    v_del       boolean := p_caller IN ('delete', 'replace');
    v_ins       boolean := p_caller IN ('insert', 'replace');
    v_fn        text := format('tgsis.%s_chunk_rows', p_caller);
    v_reg       tgsis.model_tables;
    v_face      regclass;
    v_tab       text;
    v_tab2      text;
    v_t         text;
    v_key       text[];
    v_kicols    text[];   -- the key's bigint columns
    v_kfcols    text[];   -- the key's double precision columns
    v_icols     text[];
    v_fcols     text[];
    v_bcols     text[];
    v_pcols     text[];   -- the points (role 'point': a G-map's vertex), each given as its m double rows in a row
    v_given     text[];
    v_nd        integer := 0;
    v_ni        integer := 0;
    v_dgeo      bigint[] := '{}';
    v_igeo      bigint[] := '{}';
    v_keys      text[];
    v_ids       bigint[] := '{}';
    v_vals      text;
    v_match     text;
    v_dup       text;
    v_twice     boolean := false;
    v_versioned boolean;
    v_changed   bigint[] := '{}';
BEGIN
    rows_deleted := 0;
    chunks_written := 0;
    IF NOT (v_del OR v_ins) THEN
        RAISE EXCEPTION 'tgsis.chunk_rows_write: unknown caller %', coalesce(quote_literal(p_caller), 'NULL')
            USING ERRCODE = 'TG100', HINT = 'call tgsis.delete_chunk_rows, insert_chunk_rows or replace_chunk_rows';
    END IF;
    SELECT * INTO v_reg FROM tgsis.model_tables t WHERE t.tablename = p_table AND t.chunkcolumn IS NOT NULL;
    IF NOT FOUND OR NOT tgsis.stored_in_chunks(p_table) THEN
        RAISE EXCEPTION 'tgsis.% is not stored in chunks', coalesce(quote_ident(p_table), 'NULL')
            USING ERRCODE = 'TG100',
                  DETAIL = format('%s %s the model tables switched to chunks (tgsis.stored_in_chunks).', v_fn,
                                  CASE WHEN v_ins THEN 'writes' ELSE 'deletes from' END),
                  HINT = CASE WHEN v_ins THEN 'write the rows of a table stored as rows through its view or storage'
                              ELSE 'delete the rows of a table stored as rows through its view' END;
    END IF;
    IF v_del THEN
        -- a snapshot older than the chunk table (and the catalog rows read below) is 40001, as the face's check
        PERFORM tgsis.chunk_snapshot_guard(to_regclass(format('tgsis.%I', p_table || '_chunk')));
    END IF;
    v_face := format('tgsis.%I', p_table)::regclass;
    v_key := tgsis.chunk_key(p_table) || v_reg.chunkcolumn;

    IF v_del THEN  -- the keys: exactly the key columns, the bigint ones first
        v_kicols := ARRAY(SELECT c.name FROM tgsis.chunk_columns(p_table) c
                           WHERE c.name = ANY (v_key) AND c.typename = 'bigint' ORDER BY c.colorder);
        v_kfcols := ARRAY(SELECT c.name FROM tgsis.chunk_columns(p_table) c
                           WHERE c.name = ANY (v_key) AND c.typename = 'double precision' ORDER BY c.colorder);
        v_nd := coalesce(array_length(p_delete_ints, 2), 0);
        IF p_delete_columns IS NULL OR cardinality(v_kicols || v_kfcols) <> cardinality(v_key)
           OR cardinality(p_delete_columns) <> cardinality(v_key)
           OR (SELECT array_agg(c ORDER BY c) FROM unnest(p_delete_columns[1:cardinality(v_kicols)]) AS c)
              IS DISTINCT FROM (SELECT array_agg(c ORDER BY c) FROM unnest(v_kicols) AS c)
           OR (SELECT coalesce(array_agg(c ORDER BY c), '{}') FROM unnest(p_delete_columns[cardinality(v_kicols) + 1:]) AS c)
              IS DISTINCT FROM (SELECT coalesce(array_agg(c ORDER BY c), '{}') FROM unnest(v_kfcols) AS c)
           OR array_ndims(p_delete_ints) IS DISTINCT FROM 2 OR array_length(p_delete_ints, 1) <> cardinality(v_kicols)
           OR (cardinality(v_kfcols) > 0 AND (array_ndims(p_delete_floats) IS DISTINCT FROM 2
                                              OR array_length(p_delete_floats, 1) <> cardinality(v_kfcols)
                                              OR array_length(p_delete_floats, 2) <> v_nd))
           OR (cardinality(v_kfcols) = 0 AND coalesce(cardinality(p_delete_floats), 0) > 0) THEN
            RAISE EXCEPTION 'the keys to delete from tgsis.% do not match its key', quote_ident(p_table)
                USING ERRCODE = 'TG100',
                      DETAIL = format('columns %s; ints %s for the bigint key columns (%s), floats %s for the double precision ones (%s).',
                                      coalesce(p_delete_columns::text, 'NULL'), coalesce(array_dims(p_delete_ints), 'NULL'),
                                      array_to_string(v_kicols, ', '), coalesce(array_dims(p_delete_floats), 'NULL'),
                                      array_to_string(v_kfcols, ', ')),
                      HINT = 'name every key column once, the bigint ones first, and give one row of values per column, as long as the keys';
        END IF;
    END IF;

    IF v_ins THEN  -- the rows: the row table's columns named, by type, in the caller's order
        -- the bigint ones (keys, ids, vertex ids; a smallint or integer column, a G-map involution's level, travels
        -- among them: its value is cast on insert, out of range an error as a COPY's), the double ones, the
        -- boolean ones; a column not named must be one that may be NULL (NULL then, as in a COPY)
        v_given := coalesce(p_columns, '{}');
        v_icols := ARRAY(SELECT c.name FROM tgsis.chunk_columns(p_table) c WHERE c.typename IN ('bigint', 'integer', 'smallint')
                          ORDER BY c.colorder);
        v_fcols := ARRAY(SELECT c.name FROM tgsis.chunk_columns(p_table) c WHERE c.typename = 'double precision' ORDER BY c.colorder);
        v_bcols := ARRAY(SELECT c.name FROM tgsis.chunk_columns(p_table) c WHERE c.typename = 'boolean' ORDER BY c.colorder);
        v_pcols := ARRAY(SELECT c.name FROM tgsis.chunk_columns(p_table) c WHERE c.role = 'point' ORDER BY c.colorder);
        v_ni := coalesce(array_length(p_ints, 2), 0);
        v_icols := ARRAY(SELECT c FROM unnest(v_given) WITH ORDINALITY AS u(c, o) WHERE c = ANY (v_icols) ORDER BY o);
        v_fcols := ARRAY(SELECT c FROM unnest(v_given) WITH ORDINALITY AS u(c, o) WHERE c = ANY (v_fcols) ORDER BY o);
        v_bcols := ARRAY(SELECT c FROM unnest(v_given) WITH ORDINALITY AS u(c, o) WHERE c = ANY (v_bcols) ORDER BY o);
        IF p_columns IS NULL OR v_given IS DISTINCT FROM v_icols || v_fcols || v_bcols
           -- (a point's name m times in a row, its coordinates' rows; any other once)
           OR EXISTS (SELECT FROM unnest(v_given) WITH ORDINALITY AS u(c, o) GROUP BY u.c
                       HAVING count(*) > 1 AND (NOT u.c = ANY (v_pcols) OR max(u.o) - min(u.o) + 1 <> count(*)))
           OR EXISTS (SELECT FROM tgsis.chunk_columns(p_table) c
                       JOIN pg_attribute a ON a.attrelid = tgsis.row_shape(p_table) AND a.attname = c.name
                      WHERE NOT c.name = ANY (v_given) AND (a.attnotnull OR c.role IN ('key', 'chunk', 'float', 'ref')))
           OR array_ndims(p_ints) IS DISTINCT FROM 2 OR array_length(p_ints, 1) <> cardinality(v_icols)
           OR (cardinality(v_fcols) > 0 AND (array_ndims(p_floats) IS DISTINCT FROM 2
                                             OR array_length(p_floats, 1) <> cardinality(v_fcols)
                                             OR array_length(p_floats, 2) <> v_ni))
           OR (cardinality(v_fcols) = 0 AND coalesce(cardinality(p_floats), 0) > 0)
           OR (cardinality(v_bcols) > 0 AND (array_ndims(p_bools) IS DISTINCT FROM 2
                                             OR array_length(p_bools, 1) <> cardinality(v_bcols)
                                             OR array_length(p_bools, 2) <> v_ni))
           OR (cardinality(v_bcols) = 0 AND coalesce(cardinality(p_bools), 0) > 0) THEN
            RAISE EXCEPTION 'the rows to insert into tgsis.% do not match its columns', quote_ident(p_table)
                USING ERRCODE = 'TG100',
                      DETAIL = format('columns %s; ints %s for the bigint columns, floats %s for the double precision columns, '
                                      'bools %s for the boolean columns; the columns are %s (%s may be left out: NULL).',
                                      coalesce(p_columns::text, 'NULL'), coalesce(array_dims(p_ints), 'NULL'),
                                      coalesce(array_dims(p_floats), 'NULL'), coalesce(array_dims(p_bools), 'NULL'),
                                      (SELECT string_agg(format('%s %s', c.name, c.typename), ', ' ORDER BY c.colorder)
                                         FROM tgsis.chunk_columns(p_table) c),
                                      coalesce((SELECT string_agg(c.name, ', ' ORDER BY c.colorder) FROM tgsis.chunk_columns(p_table) c
                                                  JOIN pg_attribute a ON a.attrelid = tgsis.row_shape(p_table) AND a.attname = c.name
                                                 WHERE c.role = 'value' AND NOT a.attnotnull), 'none')),
                      HINT = 'name every column once (the bigint ones, then the double precision ones, then the boolean ones) '
                             'and give one row of values per column, as long as the rows';
        END IF;
    END IF;
    IF v_nd = 0 AND v_ni = 0 THEN
        RETURN;
    END IF;

    -- the objects (geoid: the object key, the first key column)
    IF v_nd > 0 THEN
        v_dgeo := ARRAY(SELECT DISTINCT g FROM unnest(p_delete_ints[array_position(p_delete_columns, v_reg.keycolumn):array_position(p_delete_columns, v_reg.keycolumn)][:]) AS g
                         WHERE g IS NOT NULL ORDER BY g);
        IF NOT has_table_privilege(tgsis.calling_role(), v_face, 'DELETE') THEN
            RAISE EXCEPTION 'permission denied for view %', p_table
                USING ERRCODE = 'insufficient_privilege', DETAIL = format('Deleting rows of %s needs DELETE on it.', v_face),
                      HINT = 'its owner can GRANT DELETE on it';
        END IF;
        PERFORM tgsis.check_class_write(v_dgeo, 'UPDATE, DELETE');
    END IF;
    IF v_ni > 0 THEN
        v_igeo := ARRAY(SELECT DISTINCT g FROM unnest(p_ints[array_position(p_columns, v_reg.keycolumn):array_position(p_columns, v_reg.keycolumn)][:]) AS g
                         WHERE g IS NOT NULL ORDER BY g);
        IF NOT has_table_privilege(tgsis.calling_role(), v_face, 'INSERT') THEN
            RAISE EXCEPTION 'role % may not write %', quote_ident(tgsis.calling_role()), v_face
                USING ERRCODE = 'insufficient_privilege', DETAIL = 'New rows need INSERT on it.',
                      HINT = 'its owner can GRANT INSERT on it';
        END IF;
        PERFORM tgsis.check_class_write(v_igeo, 'UPDATE');
    END IF;
    v_keys := ARRAY(SELECT DISTINCT g FROM unnest(v_dgeo || v_igeo) AS g ORDER BY g)::text[];
    v_versioned := EXISTS (SELECT FROM tgsis.versioned_tables t WHERE t.schemaname = 'tgsis' AND t.tablename = p_table);
    PERFORM tgsis.object_write_prepare(p_table, v_reg.objectclass, v_keys);  -- TG301, TG303 or TG305; the locks

    -- the keys and rows, in a temporary table of tgsis's owner (the writer reads it in several statements); a
    -- second one for the rows when a key comes back with other bits (below)
    FOREACH v_t IN ARRAY ARRAY[format('pg_temp.%I', format('tgsis_%s_rows_%s', p_caller, p_table))]
                          || CASE WHEN v_nd > 0 AND v_ni > 0 THEN ARRAY[format('pg_temp.%I', format('tgsis_%s_rows2_%s', p_caller, p_table))]
                                  ELSE '{}'::text[] END LOOP
        IF to_regclass(v_t) IS NULL THEN
            EXECUTE format('CREATE TEMP TABLE %s AS SELECT *, false AS _delete FROM %s WITH NO DATA',
                           v_t, tgsis.row_shape(p_table));
        ELSIF (SELECT c.relowner FROM pg_class c WHERE c.oid = to_regclass(v_t))
              <> (SELECT r.oid FROM pg_roles r WHERE r.rolname = current_user) THEN
            RAISE EXCEPTION 'the session''s table % was not made by %', v_t, v_fn
                USING ERRCODE = 'insufficient_privilege', HINT = 'drop the temporary table and write again';
        ELSE
            EXECUTE format('TRUNCATE %s', v_t);
        END IF;
        v_tab2 := CASE WHEN v_tab IS NOT NULL THEN v_t END;
        v_tab := coalesce(v_tab, v_t);
    END LOOP;
    IF v_nd > 0 THEN  -- each key column a slice of the (columns x keys) arrays, unnested side by side
        v_vals := array_to_string(ARRAY(SELECT format('$1[%s:%s][:]', o, o) FROM generate_series(1, cardinality(v_kicols)) AS o)
                                  || ARRAY(SELECT format('$2[%s:%s][:]', o, o) FROM generate_series(1, cardinality(v_kfcols)) AS o), ', ');
        EXECUTE format('INSERT INTO %s (%s, _delete) SELECT u.*, true FROM unnest(%s) AS u',
                       v_tab, array_to_string(ARRAY(SELECT quote_ident(c) FROM unnest(p_delete_columns) AS c), ', '), v_vals)
          USING p_delete_ints, p_delete_floats;
        v_ids := ARRAY(SELECT DISTINCT i FROM unnest(p_delete_ints[array_position(p_delete_columns, v_reg.chunkcolumn):array_position(p_delete_columns, v_reg.chunkcolumn)][:]) AS i
                         WHERE i IS NOT NULL);
    END IF;
    IF v_ni > 0 THEN
        v_vals := array_to_string(ARRAY(SELECT format('$1[%s:%s][:]', o, o) FROM generate_series(1, cardinality(v_icols)) AS o)
                                  || ARRAY(SELECT format('$2[%s:%s][:]', o, o) FROM generate_series(1, cardinality(v_fcols)) AS o)
                                  || ARRAY(SELECT format('$3[%s:%s][:]', o, o) FROM generate_series(1, cardinality(v_bcols)) AS o), ', ');
        -- (a point's m rows unnested as m columns u.c<o>, written as ARRAY[...] of them)
        EXECUTE format('INSERT INTO %s (%s, _delete) SELECT %s, false FROM unnest(%s) AS u(%s)',
                       v_tab,
                       (SELECT string_agg(quote_ident(g.c), ', ' ORDER BY g.first)
                          FROM (SELECT u.c, min(u.o) AS first FROM unnest(p_columns) WITH ORDINALITY AS u(c, o) GROUP BY u.c) g),
                       (SELECT string_agg(CASE WHEN g.c = ANY (v_pcols) THEN format('ARRAY[%s]', g.cols) ELSE g.cols END, ', '
                                          ORDER BY g.first)
                          FROM (SELECT u.c, min(u.o) AS first, string_agg(format('u.c%s', u.o), ', ' ORDER BY u.o) AS cols
                                  FROM unnest(p_columns) WITH ORDINALITY AS u(c, o) GROUP BY u.c) g),
                       v_vals,
                       (SELECT string_agg(format('c%s', o), ', ' ORDER BY o) FROM generate_series(1, cardinality(p_columns)) AS o))
          USING p_ints, p_floats, p_bools;
        v_ids := v_ids || ARRAY(SELECT DISTINCT i FROM unnest(p_ints[array_position(p_columns, v_reg.chunkcolumn):array_position(p_columns, v_reg.chunkcolumn)][:]) AS i
                                 WHERE i IS NOT NULL);
    END IF;
    v_match := (SELECT string_agg(format('f.%I = r.%I', k, k), ' AND ') FROM unnest(v_key) AS k);
    -- read after the objects' write locks (no writer of them is in flight; only the chunks holding the ids decoded):
    -- the visible keys among those to delete, what a DELETE would count (the others are skipped)
    IF v_nd > 0 THEN
        EXECUTE format('SELECT count(*) FROM %s r WHERE r._delete AND EXISTS (SELECT FROM %s f WHERE %s'
                       ' AND (NOT $1 OR (%s)))',
                       v_tab, tgsis.storage_row_versions('tgsis', p_table, v_ids), v_match,
                       tgsis.visible_versions('f', '(SELECT tgsis.get_revisions(true))::integer[]'))
           INTO rows_deleted USING v_versioned;
        IF rows_deleted = 0 THEN  -- none visible: none written (as a DELETE of none)
            EXECUTE format('DELETE FROM %s r WHERE r._delete', v_tab);
        END IF;
    END IF;
    -- a row whose key is visible and not deleted here: the rows' primary key would refuse it, the face refuses it
    IF v_ni > 0 THEN
        EXECUTE format('SELECT concat_ws(%L, %s) FROM %s r WHERE NOT r._delete AND EXISTS (SELECT FROM %s f WHERE %s'
                       ' AND (NOT $1 OR (%s)))'
                       ' AND NOT EXISTS (SELECT FROM %s f WHERE f._delete AND %s) LIMIT 1',
                       ', ', (SELECT string_agg(format('r.%I', k), ', ') FROM unnest(v_key) AS k), v_tab,
                       tgsis.storage_row_versions('tgsis', p_table, v_ids), v_match,
                       tgsis.visible_versions('f', '(SELECT tgsis.get_revisions(true))::integer[]'), v_tab, v_match)
           INTO v_dup USING v_versioned;
        IF v_dup IS NOT NULL THEN
            RAISE EXCEPTION 'duplicate key value violates unique constraint "%"', p_table || '_pkey'
                USING ERRCODE = 'unique_violation',
                      DETAIL = format('Key (%s)=(%s) already exists in version %s.', array_to_string(v_key, ', '), v_dup,
                                      quote_literal(tgsis.get_working_version())),
                      CONSTRAINT = p_table || '_pkey', TABLE = p_table, SCHEMA = 'tgsis';
        END IF;
    END IF;
    IF rows_deleted > 0 AND v_ni > 0 THEN
        -- a key deleted and written again: the row replaces its deletion (its chunk written once); with other bits
        -- (-0.0 and 0.0: equal by float8 =) the rows wait for a second pass, after the deletes
        EXECUTE format('SELECT EXISTS (SELECT FROM %1$s r JOIN %1$s f ON %2$s WHERE NOT r._delete AND f._delete AND NOT (%3$s))',
                       v_tab, v_match,
                       (SELECT string_agg(CASE WHEN k = ANY (v_kfcols) THEN format('float8send(f.%I) = float8send(r.%I)', k, k)
                                               ELSE format('f.%I = r.%I', k, k) END, ' AND ')
                          FROM unnest(v_key) AS k))
           INTO v_twice;
        IF v_twice THEN
            EXECUTE format('WITH m AS (DELETE FROM %s r WHERE NOT r._delete RETURNING r.*) INSERT INTO %s SELECT * FROM m',
                           v_tab, v_tab2);
        ELSE
            EXECUTE format('DELETE FROM %s f WHERE f._delete AND EXISTS (SELECT FROM %s r WHERE NOT r._delete AND %s)',
                           v_tab, v_tab, v_match);
        END IF;
    END IF;
    IF rows_deleted > 0 OR v_ni > 0 THEN
        chunks_written := tgsis.write_chunk_rows(p_table, v_tab::regclass);  -- TG100: a NULL key, a key twice, ...
    END IF;
    IF v_twice THEN
        chunks_written := chunks_written + tgsis.write_chunk_rows(p_table, v_tab2::regclass);
        EXECUTE format('TRUNCATE %s', v_tab2);
    END IF;
    EXECUTE format('TRUNCATE %s', v_tab);
    IF v_versioned THEN
        v_changed := CASE WHEN rows_deleted > 0 THEN v_dgeo ELSE '{}' END
                     || CASE WHEN chunks_written > 0 THEN v_igeo ELSE '{}' END;
        v_keys := ARRAY(SELECT DISTINCT k FROM unnest(v_changed) AS k
                         WHERE NOT (v_reg.objectclass = 'feature'
                                    AND EXISTS (SELECT FROM tgsis.unversioned_features u WHERE u.geoid = k))
                         ORDER BY k)::text[];
        IF cardinality(v_keys) > 0 THEN
            PERFORM tgsis.record_changed_objects('tgsis', p_table, v_keys);
        END IF;
    END IF;
END
$$;

REVOKE ALL ON FUNCTION tgsis.chunk_rows_write(text, text, text[], bigint[], double precision[], text[], bigint[], double precision[], boolean[]) FROM PUBLIC;

COMMENT ON FUNCTION tgsis.chunk_rows_write(text, text, text[], bigint[], double precision[], text[], bigint[], double precision[], boolean[]) IS
    'internal: the set-based writer of tgsis.delete_chunk_rows, insert_chunk_rows and replace_chunk_rows (p_caller): the checks of a DELETE through the face for the keys and of an INSERT for the rows, the objects'' write locks, keys not visible skipped, a visible key not deleted 23505, a key deleted and written again written once; every touched chunk written once by tgsis.write_chunk_rows (a key coming back with other bits: two passes); the objects noted as changed; returns the rows deleted and the chunks written';
