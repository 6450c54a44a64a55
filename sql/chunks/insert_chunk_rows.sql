-- tgsis.insert_chunk_rows(table, columns, ints, floats, bools): insert new rows of a model table stored in chunks, for the calling role, set-based.
-- The bulk insert of the tables whose writers COPY rows (model 2's
-- times_vrtx and times_trgl: tgsis.insert_series, add_instant, the check-in
-- and merges of model 2; src/tgsis/db/_transfer.py, Storage.copy): once the
-- table is stored in chunks its name is a face, and an INSERT through it
-- rewrites a chunk per row (tgsis.chunk_face_write). Here the rows (p_ints one
-- row per bigint, integer or smallint column, p_floats one per double precision column, p_bools
-- one per boolean column, each (columns x rows), the columns named by
-- p_columns: the bigint ones, the double ones, then the boolean ones; every
-- column of the row table but those that may be NULL, which are NULL when not
-- named, as a COPY leaves them: a G-map dart's acellid and positive) are
-- written by one call of
-- the one writer of chunk contents (tgsis.write_chunk_rows: each touched
-- chunk once, in the working revision) after the checks of an INSERT through
-- the face: INSERT on the face (42501), the class's write right on every
-- object (tgsis.check_class_write), the write right on the session's version
-- and TG301 while an older revision is viewed (tgsis.write_revision), TG305
-- for unversioned storage outside DEFAULT's working revision, revision 0 for
-- features of classes without versioning (tgsis.write_chunk_rows), the
-- objects not locked by another version (TG303). The objects' write locks are
-- taken exclusively (tgsis.object_write_lock: no face write of them in
-- flight), then a row whose key is visible already is refused as the face
-- and the rows' primary key refuse it (23505 naming <table>_pkey; a COPY into
-- rows would fail the same way): an insert never replaces a row. The objects
-- are noted as changed in the working revision. As write_object_rows, it runs
-- as tgsis's owner (roles may not update chunk versions) with the rows in a
-- temporary table of its own (42501 for one the session made under that
-- name). Refused by name (TG100): a table not stored in chunks, columns that
-- are not the table's, arrays of another shape; and what
-- tgsis.write_chunk_rows refuses (NULL values, negative ids, a key twice, a
-- key equal to a stored one of other bits, a CHECK of the row table).
-- Returns the number of chunks written.
CREATE FUNCTION tgsis.insert_chunk_rows(p_table text, p_columns text[], p_ints bigint[], p_floats double precision[],
                                        p_bools boolean[] DEFAULT NULL)
RETURNS bigint
LANGUAGE plpgsql
VOLATILE
SECURITY DEFINER
SET search_path = pg_catalog, pg_temp
SET extra_float_digits = 1  -- keys compared as text below: exactly
AS $$
DECLARE
    v_reg     tgsis.model_tables;
    v_face    text;
    v_tab     text;
    v_icols   text[];
    v_fcols   text[];
    v_bcols   text[];
    v_given   text[];
    v_key     text[];
    v_n       integer;
    v_keys    text[];
    v_geoids  bigint[];
    v_vals    text;
    v_dup     text;
    v_ids     bigint[];
    v_written bigint;
    v_versioned boolean;
BEGIN
    SELECT * INTO v_reg FROM tgsis.model_tables t WHERE t.tablename = p_table AND t.chunkcolumn IS NOT NULL;
    IF NOT FOUND OR NOT tgsis.stored_in_chunks(p_table) THEN
        RAISE EXCEPTION 'tgsis.% is not stored in chunks', coalesce(quote_ident(p_table), 'NULL')
            USING ERRCODE = 'TG100',
                  DETAIL = 'tgsis.insert_chunk_rows writes the model tables switched to chunks (tgsis.stored_in_chunks).',
                  HINT = 'write the rows of a table stored as rows through its view or storage';
    END IF;
    v_face := format('tgsis.%I', p_table);
    -- the row table's columns named, by type, in the caller's order: the bigint ones (keys, ids, vertex ids), the
    -- double ones, the boolean ones; a column not named must be one that may be NULL (NULL then, as in a COPY)
    v_given := coalesce(p_columns, '{}');
    -- (a smallint or integer column, a G-map involution's level, travels among the bigint ones: its value is cast
    -- on insert, out of range an error as a COPY's)
    v_icols := ARRAY(SELECT c.name FROM tgsis.chunk_columns(p_table) c WHERE c.typename IN ('bigint', 'integer', 'smallint')
                      ORDER BY c.colorder);
    v_fcols := ARRAY(SELECT c.name FROM tgsis.chunk_columns(p_table) c WHERE c.typename = 'double precision' ORDER BY c.colorder);
    v_bcols := ARRAY(SELECT c.name FROM tgsis.chunk_columns(p_table) c WHERE c.typename = 'boolean' ORDER BY c.colorder);
    v_key := tgsis.chunk_key(p_table) || v_reg.chunkcolumn;
    v_n := coalesce(array_length(p_ints, 2), 0);
    v_icols := ARRAY(SELECT c FROM unnest(v_given) WITH ORDINALITY AS u(c, o) WHERE c = ANY (v_icols) ORDER BY o);
    v_fcols := ARRAY(SELECT c FROM unnest(v_given) WITH ORDINALITY AS u(c, o) WHERE c = ANY (v_fcols) ORDER BY o);
    v_bcols := ARRAY(SELECT c FROM unnest(v_given) WITH ORDINALITY AS u(c, o) WHERE c = ANY (v_bcols) ORDER BY o);
    IF p_columns IS NULL OR v_given IS DISTINCT FROM v_icols || v_fcols || v_bcols
       OR cardinality(v_given) <> (SELECT count(DISTINCT c) FROM unnest(v_given) AS c)
       OR EXISTS (SELECT FROM tgsis.chunk_columns(p_table) c
                   JOIN pg_attribute a ON a.attrelid = tgsis.row_shape(p_table) AND a.attname = c.name
                  WHERE NOT c.name = ANY (v_given) AND (a.attnotnull OR c.role IN ('key', 'chunk', 'float', 'ref')))
       OR array_ndims(p_ints) IS DISTINCT FROM 2 OR array_length(p_ints, 1) <> cardinality(v_icols)
       OR (cardinality(v_fcols) > 0 AND (array_ndims(p_floats) IS DISTINCT FROM 2
                                         OR array_length(p_floats, 1) <> cardinality(v_fcols)
                                         OR array_length(p_floats, 2) <> v_n))
       OR (cardinality(v_fcols) = 0 AND coalesce(cardinality(p_floats), 0) > 0)
       OR (cardinality(v_bcols) > 0 AND (array_ndims(p_bools) IS DISTINCT FROM 2
                                         OR array_length(p_bools, 1) <> cardinality(v_bcols)
                                         OR array_length(p_bools, 2) <> v_n))
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
    IF v_n = 0 THEN
        RETURN 0;
    END IF;
    -- the objects (geoid: the object key, the first key column)
    v_geoids := ARRAY(SELECT DISTINCT g FROM unnest(p_ints[array_position(p_columns, v_reg.keycolumn):array_position(p_columns, v_reg.keycolumn)][:]) AS g
                       WHERE g IS NOT NULL ORDER BY g);
    v_keys := v_geoids::text[];
    IF NOT has_table_privilege(tgsis.calling_role(), v_face::regclass, 'INSERT') THEN
        RAISE EXCEPTION 'role % may not write %', quote_ident(tgsis.calling_role()), v_face
            USING ERRCODE = 'insufficient_privilege', DETAIL = 'New rows need INSERT on it.',
                  HINT = 'its owner can GRANT INSERT on it';
    END IF;
    PERFORM tgsis.check_class_write(v_geoids, 'UPDATE');
    v_versioned := EXISTS (SELECT FROM tgsis.versioned_tables t WHERE t.schemaname = 'tgsis' AND t.tablename = p_table);
    IF v_versioned THEN
        PERFORM tgsis.write_revision();  -- TG002, TG301 before any lock is taken
        PERFORM tgsis.check_objects_unlocked(v_reg.objectclass, v_keys);
    ELSE
        PERFORM tgsis.plain_write_check('tgsis', p_table);  -- TG305
    END IF;
    PERFORM tgsis.object_write_lock(v_reg.objectclass, v_keys);

    -- the rows, in a temporary table of tgsis's owner (the writer reads it in several statements)
    v_tab := format('pg_temp.%I', 'tgsis_insert_rows_' || p_table);
    IF to_regclass(v_tab) IS NULL THEN
        EXECUTE format('CREATE TEMP TABLE %s AS SELECT *, false AS _delete FROM %s WITH NO DATA',
                       v_tab, tgsis.row_shape(p_table));
    ELSIF (SELECT c.relowner FROM pg_class c WHERE c.oid = to_regclass(v_tab))
          <> (SELECT r.oid FROM pg_roles r WHERE r.rolname = current_user) THEN
        RAISE EXCEPTION 'the session''s table % was not made by tgsis.insert_chunk_rows', v_tab
            USING ERRCODE = 'insufficient_privilege', HINT = 'drop the temporary table and write again';
    ELSE
        EXECUTE format('TRUNCATE %s', v_tab);
    END IF;
    -- each column a slice of the (columns x rows) arrays, unnested side by side
    v_vals := array_to_string(ARRAY(SELECT format('$1[%s:%s][:]', o, o) FROM generate_series(1, cardinality(v_icols)) AS o)
                              || ARRAY(SELECT format('$2[%s:%s][:]', o, o) FROM generate_series(1, cardinality(v_fcols)) AS o)
                              || ARRAY(SELECT format('$3[%s:%s][:]', o, o) FROM generate_series(1, cardinality(v_bcols)) AS o), ', ');
    EXECUTE format('INSERT INTO %s (%s, _delete) SELECT u.*, false FROM unnest(%s) AS u',
                   v_tab, array_to_string(ARRAY(SELECT quote_ident(c) FROM unnest(p_columns) AS c), ', '), v_vals)
      USING p_ints, p_floats, p_bools;
    -- a key visible already: the rows' primary key would refuse it, the face refuses it (read after the objects'
    -- write locks: no writer of them is in flight; only the chunks holding the rows' ids are decoded)
    v_ids := ARRAY(SELECT DISTINCT i FROM unnest(p_ints[array_position(p_columns, v_reg.chunkcolumn):array_position(p_columns, v_reg.chunkcolumn)][:]) AS i
                     WHERE i IS NOT NULL);
    EXECUTE format('SELECT concat_ws(%L, %s) FROM %s r WHERE EXISTS (SELECT FROM %s f WHERE %s'
                   ' AND (NOT $1 OR ((f.revision = ANY ((SELECT tgsis.get_revisions(true))::integer[])) IS TRUE'
                   ' AND (NOT f.revclosed OR NOT (f.lastrevs && (SELECT tgsis.get_revisions(true))))))) LIMIT 1',
                   ', ', (SELECT string_agg(format('r.%I', k), ', ') FROM unnest(v_key) AS k), v_tab,
                   tgsis.storage_row_versions('tgsis', p_table, v_ids),
                   (SELECT string_agg(format('f.%I = r.%I', k, k), ' AND ') FROM unnest(v_key) AS k))
       INTO v_dup USING v_versioned;
    IF v_dup IS NOT NULL THEN
        RAISE EXCEPTION 'duplicate key value violates unique constraint "%"', p_table || '_pkey'
            USING ERRCODE = 'unique_violation',
                  DETAIL = format('Key (%s)=(%s) already exists in version %s.', array_to_string(v_key, ', '), v_dup,
                                  quote_literal(tgsis.get_working_version())),
                  CONSTRAINT = p_table || '_pkey', TABLE = p_table, SCHEMA = 'tgsis';
    END IF;
    v_written := tgsis.write_chunk_rows(p_table, v_tab::regclass);
    EXECUTE format('TRUNCATE %s', v_tab);
    IF v_written > 0 AND v_versioned THEN
        v_keys := ARRAY(SELECT k FROM unnest(v_keys) AS k
                         WHERE NOT (v_reg.objectclass = 'feature'
                                    AND EXISTS (SELECT FROM tgsis.unversioned_features u WHERE u.geoid = k::bigint)));
        IF cardinality(v_keys) > 0 THEN
            PERFORM tgsis.record_changed_objects('tgsis', p_table, v_keys);
        END IF;
    END IF;
    RETURN v_written;
END
$$;

COMMENT ON FUNCTION tgsis.insert_chunk_rows(text, text[], bigint[], double precision[], boolean[]) IS
    'insert new rows of a model table stored in chunks for the calling role, set-based (INSERT on the face, the class''s write right, the version''s, object locks): the bigint columns, the double precision columns, then the boolean columns named (a column that may be NULL may be left out: NULL), their values as (columns x rows) arrays; a key visible already is 23505 as on rows; every touched chunk rewritten once by tgsis.write_chunk_rows; the objects noted as changed; returns the chunks written';
