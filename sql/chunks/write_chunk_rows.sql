-- tgsis.write_chunk_rows(table, rows): write upserts and deletes of rows into tgsis.<table>_chunk, set-based.
-- The one writer of chunk contents (docs/storage.md, "Writing an edit"): the
-- storage switch of the next step routes check-in, merge and the views'
-- triggers through it. p_rows is a table (a temporary one, usually) with the
-- row table's columns plus _delete boolean: a row with _delete true deletes
-- its key, any other row inserts or replaces it. Every touched chunk (key and
-- chunk = id >> log2(chunksize)) is handled in one set-based pass, whatever
-- the number of rows (one statement per step, no loop per row or chunk):
-- 1. which chunk versions are visible: the working set of the session's version
--    (tgsis.write_revision: the write right, TG301 while an older revision is
--    viewed) when the table is versioned (tgsis.versioned_tables), with
--    revision 0 for the features of classes without versioning
--    (tgsis.unversioned_revision); revision 0 when it is not (after
--    tgsis.plain_write_check). The registry of versioned tables decides, as
--    tgsis.storage_table does.
-- 2. they are locked in key order (SELECT ... ORDER BY key FOR UPDATE), again
--    until every visible one is locked: in READ COMMITTED a writer that waited
--    for another finds the version it waited for closed and the new one
--    committed, which the next statement sees (and locks);
-- 3. one statement decodes their present slots, merges the upserts and deletes,
--    re-encodes (holes, vbase and the differences, or _wide when one does not
--    fit integer) and writes: in place when the visible version is the working
--    revision W's, else it is closed (W appended to lastrevs) and the new
--    content inserted with revision W; a chunk left without a present slot is
--    deleted when W's, closed otherwise, and not inserted; a chunk whose content
--    stays the same bit for bit is not written at all. A new chunk that a
--    concurrent writer inserted meanwhile (its insert waited for it) is done
--    again by step 1 for those chunks only, reading what it committed.
--    Each chunk is merged on its own (a LATERAL subquery: its visible version
--    found by key, its slots unnested, joined with its few new rows and
--    aggregated in slot order), so the work grows with the chunks touched, never
--    with sorts or joins of every slot of the write at once (a scattered 1 %
--    edit touches nearly every chunk: docs/performance.md).
-- Any isolation level: in READ COMMITTED each statement sees what the writers
-- it waited for committed (the locks of step 2, the retry of step 3); in
-- REPEATABLE READ and SERIALIZABLE (a session's default isolation: psql, an
-- ORM) the transaction's snapshot stays, and a chunk version another
-- transaction changed or closed after it fails the lock of step 2, a chunk
-- it inserted the insert of step 3, with 40001 as PostgreSQL's own tables
-- answer (could not serialize access due to concurrent update): never a
-- write over what the snapshot missed. The unit of the conflict is the chunk:
-- two such transactions writing different ids of one chunk conflict
-- (docs/storage.md, "What differs from rows").
-- Refused by name: a p_rows that is not a temporary table of the session (it is read
-- by several statements: another session could change it in between), or
-- without the row table's columns (of its types) or _delete, a
-- NULL key, value (of a model table: it would be a hole) or _delete, a
-- negative id, a key twice (TG100), a NULL key or a NULL in a NOT NULL
-- property of a class's row to write (23502 naming the column, its table and
-- schema, as the row table would: the first such column in column order), a row
-- breaking a CHECK constraint of the row table (23514 naming the constraint,
-- as the table would: a vector property's value not NULL nor k values without
-- NULL breaks its column's CHECK, and the detail says what it must be). A
-- vector property (role 'vector') travels through the merge as its k
-- components <name>#i, scalar columns like the others (its old chunk's
-- slices arr[:][i:i] unnested), and is encoded again as the rows of a 2-D
-- array (k NULLs at a hole and at a NULL vector). A point (role 'point': a
-- G-map's vertex) travels as its 1-D array: the old chunk's flattened once
-- per chunk and sliced, the upserts' aggregated per chunk in slot order as
-- the rows of a 2-D array and read back by their ordinality, and the merged
-- chunk's points aggregated as the rows of its 2-D array (m NULLs at a hole,
-- m the chunk's); a point of no coordinates, or not of the length of the
-- chunk's other points that the chunk keeps (a chunk whose every point is
-- rewritten takes the new length, as the row table would store it), is
-- refused by name (TG100) before anything is locked.
-- The callers take the objects' write locks and note the changed objects
-- (tgsis.object_write_lock, tgsis.note_changed_objects), as they do for rows.
-- A double precision key (model 2's times) is compared by the float8 =
-- operator, as the row table's primary key compares it: a row whose key is
-- equal to a chunk's but not of the same bits (-0.0 written into the chunks of
-- 0.0, another NaN payload), or two rows of one write with such keys, are
-- refused by name (TG100): the chunk keeps one key for all its slots, so the
-- row's bits would be silently replaced. The chunks still to write are compared
-- as text with extra_float_digits pinned (a session's lower setting would
-- print two instants alike).
-- Returns the number of chunks written (rewritten in place, closed, inserted
-- or deleted; an unchanged one is not written). Runs with the caller's rights (tgsis's owner): internal.
CREATE FUNCTION tgsis.write_chunk_rows(p_table text, p_rows regclass)
RETURNS bigint
LANGUAGE plpgsql
VOLATILE
SET search_path = pg_catalog, pg_temp
SET extra_float_digits = 1  -- chunk keys compared as text (the chunks still to write): a double key exactly
AS $$
DECLARE
    v_reg      record;
    v_objclass text;      -- a model table's object class (tgsis.model_tables.objectclass); NULL for a class's table
    v_name     text;      -- the table as messages name it, schema-qualified
    v_notnull  text[];    -- columns a NULL value may not be written into (TG100: it would be a hole)
    v_propnn   text[];    -- a class's keys and NOT NULL properties: a NULL is 23502, as the row table answers
    v_chunk    regclass;
    v_storage  regclass;
    v_size     bigint;
    v_shift    integer;
    v_w        integer;
    v_set      integer[];
    v_geoids   bigint[];
    v_cc       text;
    v_keys     text[];    -- key columns but the chunk column, in key order
    v_fkeys    text[];    -- those of double precision (model 2's times)
    v_floats   text[];
    v_refs     text[];
    v_vals     text[];    -- every non-key column but the vector properties, in column order
    v_vecs     text[];    -- the vector properties (role 'vector': a 2-D array, slots x k)
    v_comps    text[];    -- their components, <name>#i (no property name holds '#'), written as scalar columns are
    v_pts      text[];    -- the points (role 'point': a 2-D double precision array, slots x m, m per chunk)
    v_uord     text := '';  -- ' ORDER BY u.slot' in the upserts' aggregates when a point rides in them by position
    v_first    record;    -- a class's first property column: its array's length is the chunk's
    v_missing  text;
    v_problem  text;
    v_con      record;
    v_k        text[];    -- the chunk key's columns (quoted): the keys, then chunk
    v_parts    jsonb;
    v_rows     text;      -- p_rows schema-qualified: never read as one of the statement's CTEs (k, v, m...)
    v_lock     text;
    v_unlocked text;
    v_newk     text;      -- the chunk key of a p_rows row r
    v_vis      text := '(c.revision = ANY ($1)) IS TRUE AND NOT (c.lastrevs && $1)';
    v_todo     text[];    -- NULL: every touched chunk; else the chunk keys (as text) still to write
    v_locked   text[];  -- the places (tableoid:ctid: partitioned storage is many tables) of the locked versions
    v_new      text[];
    v_more     boolean;
    v_done     bigint;
    v_total    bigint := 0;
    v_round    integer := 0;
    v_sql      text;
    v_t        text;
    v_rowrel   text;      -- the row table as the row storage's errors name it (<table>_ver when versioned)
    v_cols     jsonb;     -- tgsis.chunk_columns(p_table), read once: [{name, role, keyorder, colorder, typename, size}]
BEGIN
    v_chunk := tgsis.chunk_table_of(p_table);  -- TG200 / TG100
    SELECT * INTO v_reg FROM tgsis.chunk_registry(p_table) r;
    v_objclass := (SELECT t.objectclass FROM tgsis.model_tables t WHERE t.tablename = v_reg.tablename AND v_reg.classname IS NULL);
    v_name := tgsis.chunk_relation(p_table, '');
    v_storage := tgsis.row_shape(p_table);  -- the row definition (CHECK constraints), before or after the switch
    v_size := v_reg.chunksize;
    v_shift := round(log(2, v_reg.chunksize))::integer;
    v_cc := v_reg.chunkcolumn;
    v_keys := tgsis.chunk_key(p_table);
    v_rowrel := v_reg.tablename || CASE WHEN EXISTS (SELECT FROM tgsis.versioned_tables t WHERE t.schemaname = v_reg.schemaname
                                                                                       AND t.tablename = v_reg.tablename)
                                        THEN '_ver' ELSE '' END;
    -- the columns, read once (tgsis.chunk_columns reads the registry, the catalog and the row shape: 1.2 ms a
    -- call, which the steps below made 14 times per write)
    v_cols := (SELECT coalesce(jsonb_agg(to_jsonb(c)), '[]') FROM tgsis.chunk_columns(p_table) c);
    -- the value arrays: coordinates (float), or a class's properties (value: NULL allowed, holes marks a hole)
    v_floats := ARRAY(SELECT c.name FROM jsonb_to_recordset(v_cols) AS c(name text, role text, keyorder integer, colorder integer, typename text, size integer) WHERE c.role IN ('float', 'value') ORDER BY c.colorder);
    v_refs := ARRAY(SELECT c.name FROM jsonb_to_recordset(v_cols) AS c(name text, role text, keyorder integer, colorder integer, typename text, size integer) WHERE c.role = 'ref' ORDER BY c.colorder);
    v_vals := ARRAY(SELECT c.name FROM jsonb_to_recordset(v_cols) AS c(name text, role text, keyorder integer, colorder integer, typename text, size integer) WHERE c.role IN ('float', 'ref', 'value') ORDER BY c.colorder);
    v_vecs := ARRAY(SELECT c.name FROM jsonb_to_recordset(v_cols) AS c(name text, role text, keyorder integer, colorder integer, typename text, size integer) WHERE c.role = 'vector' ORDER BY c.colorder);
    v_comps := ARRAY(SELECT c.name || '#' || i FROM jsonb_to_recordset(v_cols) AS c(name text, role text, keyorder integer, colorder integer, typename text, size integer) CROSS JOIN LATERAL generate_series(1, c.size) AS i
                      WHERE c.role = 'vector' ORDER BY c.colorder, i);
    v_pts := ARRAY(SELECT c.name FROM jsonb_to_recordset(v_cols) AS c(name text, role text, keyorder integer, colorder integer, typename text, size integer) WHERE c.role = 'point' ORDER BY c.colorder);
    IF cardinality(v_pts) > 0 THEN
        v_uord := ' ORDER BY u.slot';
    END IF;
    SELECT c.name, c.role INTO v_first FROM jsonb_to_recordset(v_cols) AS c(name text, role text, keyorder integer, colorder integer, typename text, size integer) WHERE c.role IN ('value', 'vector') ORDER BY c.colorder LIMIT 1;
    -- a NULL value would be a hole in a model table; in a class's table only its NOT NULL columns refuse it, as the
    -- row table does (23502)
    v_notnull := ARRAY(SELECT c.name FROM jsonb_to_recordset(v_cols) AS c(name text, role text, keyorder integer, colorder integer, typename text, size integer)
                        WHERE c.role IN ('float', 'ref', 'point')
                           OR (v_reg.classname IS NULL AND c.role IN ('value', 'vector')
                               AND EXISTS (SELECT FROM pg_attribute a WHERE a.attrelid = v_storage
                                                                AND a.attname = c.name AND a.attnotnull))
                        ORDER BY c.colorder);
    v_propnn := ARRAY(SELECT c.name FROM jsonb_to_recordset(v_cols) AS c(name text, role text, keyorder integer, colorder integer, typename text, size integer)
                       WHERE v_reg.classname IS NOT NULL
                         AND (c.name = ANY (v_keys || v_cc)
                              OR (c.role IN ('value', 'vector')
                                  AND EXISTS (SELECT FROM pg_attribute a WHERE a.attrelid = v_storage
                                                                           AND a.attname = c.name AND a.attnotnull)))
                       ORDER BY c.colorder);

    -- p_rows: a temporary table of this session, read by several statements (checks, locks, the write), so that
    -- what was checked is what is written (a table other sessions write, or a view over one, changes in between)
    IF NOT EXISTS (SELECT FROM pg_class c WHERE c.oid = p_rows AND c.relkind IN ('r', 'p') AND c.relpersistence = 't') THEN
        RAISE EXCEPTION 'the rows to write into % are not in a temporary table', v_name
            USING ERRCODE = 'TG100',
                  DETAIL = format('%s is read by several statements; only a temporary table of this session cannot '
                                  'change between them.', p_rows),
                  HINT = 'copy the rows into a temporary table first';
    END IF;
    -- p_rows: the row table's columns, of its types (a cast could round a numeric id, or move a row to
    -- another key than the one checked and locked), and _delete boolean
    SELECT string_agg(format('%I %s', c.name, format_type(s.atttypid, s.atttypmod)), ', ' ORDER BY c.colorder)
      INTO v_missing
      FROM jsonb_to_recordset(v_cols) AS c(name text, role text, keyorder integer, colorder integer, typename text, size integer)
      JOIN pg_attribute s ON s.attrelid = v_storage AND s.attname = c.name
     WHERE NOT EXISTS (SELECT FROM pg_attribute a WHERE a.attrelid = p_rows AND a.attname = c.name AND a.attnum > 0
                                                   AND NOT a.attisdropped AND a.atttypid = s.atttypid);
    IF v_missing IS NOT NULL OR NOT EXISTS (SELECT FROM pg_attribute a WHERE a.attrelid = p_rows AND a.attname = '_delete'
                                                                         AND a.atttypid = 'boolean'::regtype AND NOT a.attisdropped) THEN
        RAISE EXCEPTION 'the rows to write into % lack columns', v_name
            USING ERRCODE = 'TG100',
                  DETAIL = format('%s needs the columns of %s, of its types, and _delete boolean; missing or of another type: %s.',
                                  p_rows, v_name,
                                  concat_ws(', ', v_missing, CASE WHEN NOT EXISTS (
                                      SELECT FROM pg_attribute a WHERE a.attrelid = p_rows AND a.attname = '_delete'
                                                                   AND a.atttypid = 'boolean'::regtype AND NOT a.attisdropped)
                                                                  THEN '_delete boolean' END)),
                  HINT = 'create the table of rows LIKE the row table and add the column _delete boolean';
    END IF;
    -- what the row table would refuse, refused by name (NULL marks a hole: a NULL value may not become one)
    v_newk := array_to_string(ARRAY(SELECT format('r.%I', k) FROM unnest(v_keys) AS k)
                              || format('r.%I >> %s', v_cc, v_shift), ', ');
    EXECUTE format(
        'SELECT CASE WHEN count(*) FILTER (WHERE %s) > 0 THEN %L
                     WHEN count(*) FILTER (WHERE NOT r._delete AND (%s)) > 0 THEN %L
                     WHEN count(*) FILTER (WHERE NOT r._delete AND (%s)) > 0 THEN %L
                     WHEN count(*) FILTER (WHERE r.%I < 0%s) > 0 THEN %L
                     WHEN count(*) <> count(DISTINCT (%s, r.%I)) THEN %L END
           FROM %s r',
        -- (a class's row to write with a NULL key: 23502 below, as the row table answers)
        concat_ws(' OR ', 'r._delete IS NULL',
                  CASE WHEN v_reg.classname IS NOT NULL THEN 'r._delete AND (' ELSE '' END
                  || (SELECT string_agg(format('r.%I IS NULL', k), ' OR ') FROM unnest(v_keys || v_cc) AS k)
                  || CASE WHEN v_reg.classname IS NOT NULL THEN ')' ELSE '' END),
        'a key or _delete is NULL',
        coalesce((SELECT string_agg(format('r.%I IS NULL', v), ' OR ') FROM unnest(v_notnull) AS v), 'false'),
        'a row to write has a NULL value',
        coalesce((SELECT string_agg(format('r.%I IS NULL', v), ' OR ') FROM unnest(v_propnn) AS v), 'false'),
        '23502',
        v_cc, (SELECT string_agg(format(' OR (NOT r._delete AND r.%I < 0)', v), '') FROM unnest(v_refs) AS v),
        'a row has a negative id',
        array_to_string(ARRAY(SELECT format('r.%I', k) FROM unnest(v_keys) AS k), ', '), v_cc,
        'a key is given twice',
        p_rows) INTO v_problem;
    IF v_problem = '23502' THEN
        -- a NULL key or a NULL in a NOT NULL property of a class: the row table's answer (its message, the column, table and schema
        -- in diag), the first such column in column order
        FOREACH v_t IN ARRAY v_propnn LOOP
            EXECUTE format('SELECT EXISTS (SELECT FROM %s r WHERE NOT r._delete AND r.%I IS NULL)', p_rows, v_t) INTO v_more;
            IF v_more THEN
                RAISE EXCEPTION 'null value in column "%" of relation "%" violates not-null constraint', v_t, v_rowrel
                    USING ERRCODE = 'not_null_violation', COLUMN = v_t, TABLE = v_rowrel, SCHEMA = v_reg.schemaname,
                          DETAIL = format('Column %I of %s is NOT NULL; written into %s by chunks, nothing was written.',
                                          v_t, v_name, v_chunk),
                          HINT = format('give %I a value in every row', v_t);
            END IF;
        END LOOP;
    END IF;
    IF v_problem IS NOT NULL THEN
        RAISE EXCEPTION 'cannot write these rows into %: %', v_name, v_problem
            USING ERRCODE = 'TG100',
                  DETAIL = format('Ids are 0 or more, the columns of %s are NOT NULL (%s), and each key is written once by one call.',
                                  v_name, coalesce(array_to_string(v_notnull || v_propnn, ', '), 'none')),
                  HINT = 'give each key once, with all its values';
    END IF;
    -- the row table's CHECKs, in name order as PostgreSQL checks them: 23514 naming the row table and the constraint
    -- (diag's constraint, table and schema too), as the row table answers; a vector property's (a column CHECK of its
    -- one column: k values from 1, none NULL) says what its value must be
    FOR v_con IN SELECT con.conname, pg_get_expr(con.conbin, con.conrelid) AS expr, c.name AS vector, c.size
                   FROM pg_constraint con
                   LEFT JOIN pg_attribute a ON a.attrelid = con.conrelid AND con.conkey = ARRAY[a.attnum]
                   LEFT JOIN jsonb_to_recordset(v_cols) AS c(name text, role text, keyorder integer, colorder integer, typename text, size integer) ON c.role = 'vector' AND c.name = a.attname
                  WHERE con.conrelid = v_storage AND con.contype = 'c'
                    AND con.conname <> v_reg.tablename || '_shape_holds_no_rows' ORDER BY con.conname LOOP
        EXECUTE format('SELECT EXISTS (SELECT FROM %s WHERE NOT _delete AND NOT (%s))', p_rows, v_con.expr) INTO v_more;
        IF v_more AND v_con.vector IS NOT NULL THEN
            RAISE EXCEPTION 'new row for relation "%" violates check constraint "%"', v_rowrel, v_con.conname
                USING ERRCODE = 'check_violation', CONSTRAINT = v_con.conname, TABLE = v_rowrel, SCHEMA = v_reg.schemaname,
                      DETAIL = format('A value of vector property %I of %s is not NULL nor a one-dimensional array '
                                      'from 1 of exactly %s values without NULL; nothing was written.',
                                      v_con.vector, v_name, v_con.size),
                      HINT = 'give each vector property exactly its number of components, or NULL for no value';
        ELSIF v_more THEN
            RAISE EXCEPTION 'new row for relation "%" violates check constraint "%"', v_rowrel, v_con.conname
                USING ERRCODE = 'check_violation', CONSTRAINT = v_con.conname, TABLE = v_rowrel, SCHEMA = v_reg.schemaname,
                      DETAIL = format('Written into %s by chunks; nothing was written.', v_chunk);
        END IF;
    END LOOP;

    -- the working revision and the set it sees
    IF EXISTS (SELECT FROM tgsis.versioned_tables t WHERE t.schemaname = v_reg.schemaname AND t.tablename = v_reg.tablename) THEN
        EXECUTE format('SELECT array_agg(DISTINCT r.%I) FROM %s r', v_reg.keycolumn, p_rows) INTO v_geoids;
        IF v_objclass = 'feature'
           AND EXISTS (SELECT FROM tgsis.unversioned_features u WHERE u.geoid = ANY (v_geoids)) THEN
            v_w := tgsis.unversioned_revision(v_geoids);  -- TG305, TG300
            v_set := ARRAY[0];
        ELSE
            SELECT w.revision, w.revisions INTO v_w, v_set FROM tgsis.write_revision() AS w;
        END IF;
    ELSE
        PERFORM tgsis.plain_write_check(v_reg.schemaname, v_reg.tablename);  -- TG305
        v_w := 0;
        v_set := ARRAY[0];
    END IF;

    -- a double precision key (times) equal but not of the same bits as the chunk's or another row's: refused, the
    -- chunk has one key for all its slots (tgsis.chunk_key says how such keys compare)
    v_fkeys := ARRAY(SELECT c.name FROM jsonb_to_recordset(v_cols) AS c(name text, role text, keyorder integer, colorder integer, typename text, size integer) WHERE c.role = 'key' AND c.typename = 'double precision'
                      ORDER BY c.keyorder);
    IF cardinality(v_fkeys) > 0 THEN
        EXECUTE format(
            'SELECT coalesce((SELECT concat_ws(%5$L, %1$s) FROM (SELECT DISTINCT %1$s, %10$s FROM %2$s r) r
                                WHERE EXISTS (SELECT FROM %3$s c WHERE %4$s AND (%6$s) AND NOT (%7$s))
                                LIMIT 1),
                             (SELECT concat_ws(%5$L, %8$s) FROM %2$s r GROUP BY %9$s
                              HAVING count(DISTINCT (%10$s)) > 1 LIMIT 1))',
            (SELECT string_agg(format('r.%I', k), ', ') FROM unnest(v_keys) AS k), p_rows, v_chunk, v_vis, ', ',
            (SELECT string_agg(format('c.%I = r.%I', k, k), ' AND ') FROM unnest(v_keys) AS k),
            (SELECT string_agg(format('float8send(c.%I) = float8send(r.%I)', k, k), ' AND ') FROM unnest(v_fkeys) AS k),
            (SELECT string_agg(format('min(r.%I)', k), ', ') FROM unnest(v_keys) AS k),
            (SELECT string_agg(format('r.%I', k), ', ') FROM unnest(v_keys) AS k),
            (SELECT string_agg(format('float8send(r.%I)', k), ', ') FROM unnest(v_fkeys) AS k))
           INTO v_problem USING v_set;
        IF v_problem IS NOT NULL THEN
            RAISE EXCEPTION 'cannot write these rows into %: key (%) is equal to a stored or written key of other bits',
                            v_name, v_problem
                USING ERRCODE = 'TG100',
                      DETAIL = format('%s compare as the primary key of the rows does (-0.0 = 0.0, NaN = NaN); the chunk of a '
                                      'key keeps one value for all its rows, so other bits would be silently replaced.',
                                      array_to_string(v_fkeys, ', ')),
                      HINT = 'write the key with the bits it is stored with (read it back from the table)';
        END IF;
    END IF;

    -- a point (role 'point') is a row of its chunk's 2-D array: every point written into a chunk has the length of
    -- the chunk's others that it keeps (present slots neither rewritten nor deleted by these rows), or of another
    -- chunk of the object when the chunk is new (m, the object's embedding), and at least one coordinate; refused by
    -- name (TG100), as the switch refuses such an object (tgsis.store_in_chunks), before anything is locked or
    -- written. A chunk whose every point is rewritten takes the written points' length: an object whose points are
    -- all of one other length than its embedding (as the row table holds them, tgsis.check_geometry reports them)
    -- is mended through the face as on rows
    FOREACH v_missing IN ARRAY v_pts LOOP
        EXECUTE format(
            'SELECT format(%1$L, concat_ws(%2$L, %3$s), n.id, n.lo, n.hi, v.m)
               FROM (SELECT %4$s, min(r.%5$I) FILTER (WHERE NOT r._delete) AS id,
                            min(coalesce(cardinality(r.%6$I), 0)) FILTER (WHERE NOT r._delete) AS lo,
                            max(coalesce(cardinality(r.%6$I), 0)) FILTER (WHERE NOT r._delete) AS hi,
                            array_agg(DISTINCT r.%5$I) AS ids
                       FROM %7$s r GROUP BY %8$s) n
               LEFT JOIN LATERAL (SELECT array_length(c.%6$I, 2) AS m,
                                         -- the chunk itself keeps a point these rows leave (its present slots, 1-based,
                                         -- below its last present one but the holes, outnumber those written here)
                                         c.chunk <> n.chunk
                                         OR array_length(c.%6$I, 1) - coalesce(cardinality(c.holes), 0)
                                            > (SELECT count(*) FROM unnest(n.ids) AS i
                                                WHERE i - (n.chunk << %13$s) + 1 <= array_length(c.%6$I, 1)
                                                  AND NOT (i - (n.chunk << %13$s) + 1) = ANY (coalesce(c.holes, %14$L))) AS kept
                                    FROM %9$s c WHERE %10$s AND %11$s
                                   ORDER BY c.chunk = n.chunk DESC LIMIT 1) v ON true
              WHERE n.lo = 0 OR n.lo <> n.hi OR (v.kept AND n.lo <> v.m)
              ORDER BY %12$s LIMIT 1',
            '(%s), from id %s: points of %s to %s coordinates, the chunk''s others %s', ', ',
            (SELECT string_agg(format('n.%I', k), ', ' ORDER BY o) FROM unnest(v_keys) WITH ORDINALITY AS u(k, o)),
            array_to_string(ARRAY(SELECT format('r.%I AS %I', k, k) FROM unnest(v_keys) AS k)
                            || format('r.%I >> %s AS chunk', v_cc, v_shift), ', '),
            v_cc, v_missing, p_rows,
            array_to_string(ARRAY(SELECT format('r.%I', k) FROM unnest(v_keys) AS k) || format('r.%I >> %s', v_cc, v_shift), ', '),
            v_chunk,
            -- (the chunk's visible version, else another of the object's: a new chunk takes the object's m)
            array_to_string(ARRAY(SELECT format('c.%1$I = n.%1$I', k) FROM unnest(v_keys) AS k), ' AND '),
            v_vis,
            array_to_string(ARRAY(SELECT format('n.%I', k) FROM unnest(v_keys) AS k) || 'n.chunk'::text, ', '),
            v_shift, '{}')
           INTO v_problem USING v_set;
        IF v_problem IS NOT NULL THEN
            RAISE EXCEPTION 'cannot write these rows into %: the points of a chunk are not all of one length', v_name
                USING ERRCODE = 'TG100',
                      DETAIL = format('Object %s; a chunk holds its points as the rows of a 2-D array, m coordinates each '
                                      '(the embedding''s, at least one) in column %I; nothing was written.', v_problem, v_missing),
                      HINT = 'give every point of the object its embedding''s m coordinates';
        END IF;
    END LOOP;

    -- the writing statement, from a template whose {parts} are made by format() from the column lists
    SELECT format('%I.%I', s.nspname, c.relname) INTO v_rows
      FROM pg_class c JOIN pg_namespace s ON s.oid = c.relnamespace WHERE c.oid = p_rows;
    v_k := ARRAY(SELECT quote_ident(k) FROM unnest(v_keys) AS k) || 'chunk'::text;
    v_parts := jsonb_build_object(
        'rows', v_rows,
        'chunk', v_chunk::text,
        'vis', v_vis,
        'todo', format('($3::text[] IS NULL OR ROW(%s)::text = ANY ($3))', v_newk),
        'newk_as', array_to_string(ARRAY(SELECT format('r.%I AS %I', k, k) FROM unnest(v_keys) AS k)
                                   || format('r.%I >> %s AS chunk', v_cc, v_shift), ', '),
        'cc', quote_ident(v_cc),
        'mask', v_size - 1,
        'K', array_to_string(v_k, ', '),
        'n_K', array_to_string(ARRAY(SELECT 'n.' || k FROM unnest(v_k) AS k), ', '),
        'k_K', array_to_string(ARRAY(SELECT 'k.' || k FROM unnest(v_k) AS k), ', '),
        'c_K', array_to_string(ARRAY(SELECT 'c.' || k FROM unnest(v_k) AS k), ', '),
        'i_K', array_to_string(ARRAY(SELECT 'i.' || k FROM unnest(v_k) AS k), ', '),
        'match_c_k', array_to_string(ARRAY(SELECT format('c.%s = k.%s', k, k) FROM unnest(v_k) AS k), ' AND '),
        'arrays', array_to_string(ARRAY(SELECT format('v.%I', f) FROM unnest(v_floats) AS f)
                                  -- (a point's first coordinates: NULL at a hole; the slot's point is sliced from the
                                  -- chunk's flattened array, {pflat})
                                  || ARRAY(SELECT format('v.%I[:][1:1]', pt) FROM unnest(v_pts) AS pt)
                                  -- (a vector property's components: the slices arr[:][i:i] of its 2-D array)
                                  || ARRAY(SELECT format('v.%I[:][%s:%s]', split_part(x, '#', 1), split_part(x, '#', 2),
                                                         split_part(x, '#', 2)) FROM unnest(v_comps) AS x)
                                  || ARRAY(SELECT format('v.%I, v.%I', r, r || '_wide') FROM unnest(v_refs) AS r), ', '),
        'alias', array_to_string(ARRAY(SELECT quote_ident(f) FROM unnest(v_floats || ARRAY(SELECT pt || '#1' FROM unnest(v_pts) AS pt)
                                                                          || v_comps) AS f)
                                 || ARRAY(SELECT format('%I, %I', r, r || '_wide') FROM unnest(v_refs) AS r), ', '),
        -- a slot present in the merged chunk: a model table's first double precision or vertex-id column is NOT NULL
        -- exactly there (those columns are NOT NULL; its 'value' columns, a G-map dart's acellid, may be NULL); a
        -- class's property may be NULL, so there an old slot is present when it is within the old arrays and not
        -- one of their holes, a new one when it is not deleted
        'mpresent', CASE WHEN v_reg.classname IS NOT NULL THEN 'm._present'
                         ELSE format('m.%I IS NOT NULL',
                                     (SELECT c.name FROM jsonb_to_recordset(v_cols) AS c(name text, role text, keyorder integer, colorder integer, typename text, size integer) WHERE c.role IN ('float', 'ref', 'point')
                                       ORDER BY c.colorder LIMIT 1)) END,
        'presentcol', CASE WHEN v_reg.classname IS NOT NULL
                           THEN format(', CASE WHEN u.slot IS NULL THEN o.slot <= coalesce(%s(v.%I%s), 0) '
                                       'AND NOT coalesce(o.slot = ANY (v.holes), false) ELSE NOT u._delete END AS _present',
                                       CASE WHEN v_first.role = 'vector' THEN 'array_length' ELSE 'cardinality' END, v_first.name,
                                       CASE WHEN v_first.role = 'vector' THEN ', 1' ELSE '' END)
                           ELSE '' END,
        'u_K', array_to_string(ARRAY(SELECT 'u.' || k FROM unnest(v_k) AS k), ', '),
        'match_ug_k', array_to_string(ARRAY(SELECT format('ug.%s = k.%s', k, k) FROM unnest(v_k) AS k), ' AND '),
        'uord', v_uord,
        'uarr', array_to_string(ARRAY(SELECT format('array_agg(u.%I%s) AS %I', c, v_uord, c) FROM unnest(v_vals || v_comps) AS c)
                                -- a point: the chunk's upserts' points as the rows of a 2-D array in slot order (a
                                -- delete's row m NULLs), read back by the upsert's ordinality ui
                                || ARRAY(SELECT format('array_agg(coalesce(u.%1$I, array_fill(NULL::double precision, ARRAY[u.%2$I])) '
                                                       'ORDER BY u.slot) AS %1$I', pt, pt || '#m') FROM unnest(v_pts) AS pt), ', '),
        'ugarr', array_to_string(ARRAY(SELECT format(', ug.%I', c) FROM unnest(v_vals || v_comps) AS c), ''),
        'unames', array_to_string(ARRAY(SELECT format(', %I', c) FROM unnest(v_vals || v_comps) AS c), ''),
        -- a point's chunk length m: its points' (one length: checked above)
        'pm', coalesce((SELECT string_agg(format(', max(cardinality(m.%I)) AS %I', pt, pt || '#m'), '') FROM unnest(v_pts) AS pt), ''),
        -- a point's arrays flattened once per chunk (a MATERIALIZED CTE of the chunk's LATERAL subquery, joined by
        -- m): the old chunk's (flat, m) and the upserts' (uflat, um)
        -- (NULLs, at holes and deletes, made 0 and never read: no slice carries a NULL bitmap, which array_agg would keep)
        'pflat', coalesce((SELECT string_agg(format('%2$I AS MATERIALIZED (SELECT ARRAY(SELECT coalesce(x, 0) FROM unnest(v.%1$I) AS x) AS flat, '
                                                    'array_length(v.%1$I, 2) AS m, ARRAY(SELECT coalesce(x, 0) FROM unnest(ug.%1$I) AS x) AS uflat, '
                                                    'array_length(ug.%1$I, 2) AS um), ', pt, 'p#' || pt), '')
                             FROM unnest(v_pts) AS pt), ''),
        'pjoin', coalesce((SELECT string_agg(format(' CROSS JOIN %I', 'p#' || pt), '') FROM unnest(v_pts) AS pt), ''),
        'mvals', array_to_string(ARRAY(
            SELECT format('CASE WHEN u.slot IS NULL THEN %s WHEN NOT u._delete THEN u.%I END AS %I',
                          CASE WHEN c = ANY (v_refs)
                               THEN format('CASE WHEN v.vbase IS NOT NULL THEN v.vbase + %s ELSE o.%I END',
                                           CASE WHEN c = v_refs[1] THEN format('o.%I', c) ELSE format('o.%I + o.%I', v_refs[1], c) END,
                                           c || '_wide')
                               ELSE format('o.%I', c) END, c, c)
              FROM unnest(v_vals || v_comps) AS c)
            -- a point: the old chunk's slot sliced from its flattened array, or the upsert's from the upserts' (ui)
            || ARRAY(SELECT format('CASE WHEN u.slot IS NULL THEN CASE WHEN o.%1$I IS NOT NULL '
                                   'THEN %2$I.flat[(o.slot - 1) * %2$I.m + 1 : o.slot * %2$I.m] END '
                                   'WHEN NOT u._delete THEN %2$I.uflat[(u.ui - 1) * %2$I.um + 1 : u.ui * %2$I.um] END AS %3$I',
                                   pt || '#1', 'p#' || pt, pt)
                       FROM unnest(v_pts) AS pt), ', '),
        'rvals', array_to_string(ARRAY(SELECT format('r.%I::%s AS %I', c.name, c.typename, c.name)
                                         FROM jsonb_to_recordset(v_cols) AS c(name text, role text, keyorder integer, colorder integer, typename text, size integer) WHERE c.role IN ('float', 'value') ORDER BY c.colorder)
                                 || ARRAY(SELECT format('r.%I::bigint AS %I', r, r) FROM unnest(v_refs) AS r)
                                 || ARRAY(SELECT format('(r.%I)[%s] AS %I', split_part(x, '#', 1), split_part(x, '#', 2), x)
                                            FROM unnest(v_comps) AS x)
                                 -- a point, and its chunk's m (every written point of a chunk has it: checked above)
                                 || ARRAY(SELECT format('CASE WHEN NOT r._delete THEN r.%1$I END AS %1$I, '
                                                        'coalesce(max(cardinality(r.%1$I)) FILTER (WHERE NOT r._delete) '
                                                        'OVER (PARTITION BY %2$s), 1) AS %3$I', pt, v_newk, pt || '#m')
                                            FROM unnest(v_pts) AS pt), ', '),
        -- a chunk's refs are relative when every difference fits integer, else absolute in the _wide columns
        -- (and the maxima of vtop, the chunk's bound of its vertex ids: vbase + 2 * the largest relative value, or
        -- the largest _wide id; chunk_encoding_checks says why twice)
        'fit', CASE WHEN cardinality(v_refs) = 0 THEN 'NULL::bigint AS vmin, true AS fits, NULL::bigint AS vtop'
                    ELSE format('min(least(%1$s)) AS vmin, '
                                'coalesce(max(m.%2$I) - min(least(%1$s)) <= 2147483647%3$s, true) AS fits, '
                                'CASE WHEN coalesce(max(m.%2$I) - min(least(%1$s)) <= 2147483647%3$s, true) '
                                'THEN least(min(least(%1$s))::numeric + 2 * greatest(0, max(m.%2$I) - min(least(%1$s))%4$s), '
                                '9223372036854775807)::bigint ELSE max(greatest(%1$s)) END AS vtop',
                                array_to_string(ARRAY(SELECT format('m.%I', r) FROM unnest(v_refs) AS r), ', '), v_refs[1],
                                coalesce((SELECT string_agg(format(' AND min(m.%1$I - m.%2$I) >= -2147483648'
                                                                   ' AND max(m.%1$I - m.%2$I) <= 2147483647', r, v_refs[1]), '')
                                            FROM unnest(v_refs[2:]) AS r), ''),
                                coalesce((SELECT string_agg(format(', max(m.%1$I - m.%2$I)', r, v_refs[1]), '')
                                            FROM unnest(v_refs[2:]) AS r), '')) END,
        -- (the FILTERs: the columns a chunk does not use are not sorted)
        'enc', array_to_string(
            ARRAY(SELECT format('array_agg(m.%I ORDER BY m.slot) AS %I', f, f) FROM unnest(v_floats) AS f)
            -- a vector property: the slots' vectors as the rows of a 2-D array (k NULLs at a hole and a NULL vector)
            || ARRAY(SELECT format('array_agg(ARRAY[%s] ORDER BY m.slot) AS %I',
                                   (SELECT string_agg(format('m.%I', x), ', ' ORDER BY i)
                                      FROM unnest(v_comps) WITH ORDINALITY AS y(x, i) WHERE split_part(x, '#', 1) = vv), vv)
                       FROM unnest(v_vecs) AS vv)
            -- a point: the slots' points as the rows of a 2-D array (m NULLs at a hole)
            || ARRAY(SELECT format('array_agg(coalesce(m.%1$I, array_fill(NULL::double precision, ARRAY[e.%2$I])) ORDER BY m.slot) AS %1$I',
                                   pt, pt || '#m')
                       FROM unnest(v_pts) AS pt)
            || ARRAY(SELECT format('CASE WHEN e.fits THEN array_agg(CASE WHEN e.fits THEN (m.%I - %s)::integer END ORDER BY m.slot) FILTER (WHERE e.fits) END AS %I',
                                   r, CASE WHEN r = v_refs[1] THEN 'e.vmin' ELSE format('m.%I', v_refs[1]) END, r)
                     FROM unnest(v_refs) AS r)
            || ARRAY(SELECT format('CASE WHEN NOT e.fits THEN array_agg(m.%I ORDER BY m.slot) FILTER (WHERE NOT e.fits) END AS %I', r, r || '_wide')
                     FROM unnest(v_refs) AS r), ', '),
        'setcols', array_to_string(ARRAY['holes = n.holes']
                                   || CASE WHEN cardinality(v_refs) > 0 THEN ARRAY['vbase = n.vbase', 'vtop = n.vtop'] ELSE '{}'::text[] END
                                   || ARRAY(SELECT format('%I = n.%I', c, c) FROM unnest(v_vals || v_vecs || v_pts) AS c)
                                   || ARRAY(SELECT format('%I = n.%I', r || '_wide', r || '_wide') FROM unnest(v_refs) AS r), ', '),
        'inscols', array_to_string(v_k || ARRAY['revision', 'holes']
                                   || CASE WHEN cardinality(v_refs) > 0 THEN ARRAY['vbase', 'vtop'] ELSE '{}'::text[] END
                                   || ARRAY(SELECT quote_ident(c) FROM unnest(v_vals || v_vecs || v_pts) AS c)
                                   || ARRAY(SELECT quote_ident(r || '_wide') FROM unnest(v_refs) AS r), ', '),
        -- a chunk whose new content is the visible one bit for bit (array_send: -0.0 is not 0.0) is not written
        'same', array_to_string(ARRAY['z.holes IS NOT DISTINCT FROM v.holes']
                                || CASE WHEN cardinality(v_refs) > 0 THEN ARRAY['z.vbase IS NOT DISTINCT FROM v.vbase'] ELSE '{}'::text[] END
                                || ARRAY(SELECT format('array_send(z.%1$I) IS NOT DISTINCT FROM array_send(v.%1$I)', c)
                                           FROM unnest(v_vals || v_vecs || v_pts || ARRAY(SELECT r || '_wide' FROM unnest(v_refs) AS r)) AS c),
                                ' AND '),
        'insvals', array_to_string(ARRAY(SELECT 'n.' || k FROM unnest(v_k) AS k) || ARRAY['$2', 'n.holes']
                                   || CASE WHEN cardinality(v_refs) > 0 THEN ARRAY['n.vbase', 'n.vtop'] ELSE '{}'::text[] END
                                   || ARRAY(SELECT 'n.' || quote_ident(c) FROM unnest(v_vals || v_vecs || v_pts) AS c)
                                   || ARRAY(SELECT 'n.' || quote_ident(r || '_wide') FROM unnest(v_refs) AS r), ', '));
    v_sql := $q$
WITH k AS (
    SELECT DISTINCT {newk_as} FROM {rows} r WHERE {todo}
), upsert AS (
    SELECT {newk_as}, (r.{cc} & {mask}) + 1 AS slot, r._delete, {rvals} FROM {rows} r WHERE {todo}
), ug AS (  -- the upserts and deletes of each touched chunk, as arrays (a few per chunk)
    SELECT {u_K}, max(u.slot) AS umax, array_agg(u.slot{uord}) AS uslot, array_agg(u._delete{uord}) AS udel, {uarr}
      FROM upsert u GROUP BY {u_K}
), en AS (  -- each touched chunk merged and encoded on its own (its slots sorted in memory, not the whole write's)
    SELECT {k_K}, v.vtoid, v.vtid, v.revision AS vrev, z.*,
           (v.vtid IS NOT NULL AND z.last IS NOT NULL AND {same}) AS unchanged
      FROM k JOIN ug ON {match_ug_k}
      LEFT JOIN LATERAL (  -- the visible version, found by key (the primary key's index)
        SELECT c.tableoid AS vtoid, c.ctid AS vtid, c.* FROM {chunk} c WHERE {match_c_k} AND {vis}
      ) v ON true
     CROSS JOIN LATERAL (
        WITH {pflat}m AS MATERIALIZED (  -- every slot up to the last old or new one: the value written (NULL: a hole)
            SELECT o.slot, {mvals}{presentcol}  -- (the NULL array as long as the last new slot extends the old arrays to it)
              FROM unnest({arrays}, array_fill(NULL::integer, ARRAY[ug.umax::integer])) WITH ORDINALITY AS o({alias}, pad, slot){pjoin}
              LEFT JOIN unnest(ug.uslot, ug.udel{ugarr}) WITH ORDINALITY AS u(slot, _delete{unames}, ui) ON u.slot = o.slot
        ), e AS (
            SELECT max(m.slot) FILTER (WHERE {mpresent}) AS last, {fit}{pm} FROM m
        )
        SELECT e.last, CASE WHEN e.fits THEN e.vmin END AS vbase, e.vtop, f.*
          FROM e LEFT JOIN LATERAL (
            SELECT array_agg(m.slot::smallint ORDER BY m.slot) FILTER (WHERE NOT {mpresent}) AS holes, {enc}
              FROM m WHERE m.slot <= e.last
          ) f ON true
     ) z
), e AS (  -- every touched chunk: its visible version (vtoid, vtid, vrev: NULL when none) and new content (last NULL: none)
    SELECT * FROM en
), n AS (
    SELECT * FROM en WHERE en.last IS NOT NULL
), upd AS (
    UPDATE {chunk} c SET {setcols} FROM n
     WHERE c.tableoid = n.vtoid AND c.ctid = n.vtid AND n.vrev = $2 AND NOT n.unchanged
    RETURNING {c_K}
), del AS (
    DELETE FROM {chunk} c USING e
     WHERE c.tableoid = e.vtoid AND c.ctid = e.vtid AND e.vrev = $2 AND e.last IS NULL
    RETURNING {c_K}
), cls AS (
    UPDATE {chunk} c SET lastrevs = c.lastrevs || $2 FROM e
     WHERE c.tableoid = e.vtoid AND c.ctid = e.vtid AND e.vrev <> $2 AND NOT e.unchanged
    RETURNING {c_K}
), fresh AS (  -- the new versions: no visible one is W's or already holds this content
    SELECT n.* FROM n WHERE NOT (n.vtid IS NOT NULL AND (n.vrev = $2 OR n.unchanged))
), ins AS (
    INSERT INTO {chunk} ({inscols})
    SELECT {insvals} FROM fresh n
     ORDER BY {n_K}  -- new keys in key order, as the locks: two writers adding the same chunks do not deadlock
    ON CONFLICT DO NOTHING
    RETURNING {K}
)
SELECT (SELECT count(*) FROM (SELECT * FROM upd UNION SELECT * FROM del UNION SELECT * FROM cls UNION SELECT * FROM ins) w),
       ARRAY(SELECT ROW({n_K})::text FROM fresh n EXCEPT SELECT ROW({i_K})::text FROM ins i)
$q$;
    -- one pass over the template: a part's text (a table's name may hold '{cc}') is never searched for placeholders
    SELECT string_agg(CASE WHEN t.m[1] IS NULL THEN t.m[2] ELSE v_parts->>substr(t.m[1], 2, length(t.m[1]) - 2) END,
                      '' ORDER BY t.o)
      INTO v_sql
      FROM regexp_matches(v_sql, '(\{[A-Za-z_]+\})|([^{]+|\{)', 'g') WITH ORDINALITY AS t(m, o);
    v_lock := format(
        'SELECT coalesce(array_agg(l.t), ''{}'') FROM (
           SELECT c.tableoid::text || '':'' || c.ctid::text AS t FROM %1$s c
            WHERE (%2$s) IN (SELECT %3$s FROM %4$s r WHERE ($3::text[] IS NULL OR ROW(%3$s)::text = ANY ($3)))
              AND %5$s AND c.tableoid::text || '':'' || c.ctid::text <> ALL ($4)
            ORDER BY %2$s FOR UPDATE OF c) l',
        v_chunk, v_parts->>'c_K', v_newk, v_rows, v_vis);
    v_unlocked := format(
        'SELECT EXISTS (SELECT FROM %1$s c
            WHERE (%2$s) IN (SELECT %3$s FROM %4$s r WHERE ($3::text[] IS NULL OR ROW(%3$s)::text = ANY ($3)))
              AND %5$s AND c.tableoid::text || '':'' || c.ctid::text <> ALL ($4))',
        v_chunk, v_parts->>'c_K', v_newk, v_rows, v_vis);

    LOOP
        v_round := v_round + 1;
        -- lock the visible versions of the touched chunks in key order, until every visible one is locked
        v_locked := '{}';
        LOOP
            EXECUTE v_lock INTO v_new USING v_set, v_w, v_todo, v_locked;
            v_locked := v_locked || v_new;
            EXECUTE v_unlocked INTO v_more USING v_set, v_w, v_todo, v_locked;
            EXIT WHEN NOT v_more;
        END LOOP;
        -- decode, merge, encode and write ($1 the set, $2 W, $3 the chunks still to write: NULL for all)
        EXECUTE v_sql INTO v_done, v_todo USING v_set, v_w, v_todo;
        v_total := v_total + v_done;
        EXIT WHEN cardinality(v_todo) = 0;
        -- new chunks a concurrent writer inserted first: again, reading what it committed
        IF v_round >= 5 THEN
            RAISE EXCEPTION 'chunks of % kept changing while this write waited for them', v_name
                USING ERRCODE = 'serialization_failure', DETAIL = format('Still to write: %s.', array_to_string(v_todo, ', ')),
                      HINT = 'retry the transaction';
        END IF;
    END LOOP;
    RETURN v_total;
END
$$;

REVOKE ALL ON FUNCTION tgsis.write_chunk_rows(text, regclass) FROM PUBLIC;

COMMENT ON FUNCTION tgsis.write_chunk_rows(text, regclass) IS
    'write the rows of a table (the row table''s columns plus _delete boolean: true deletes the key) into tgsis.<table>_chunk in one set-based pass: the touched chunks'' visible versions locked in key order, merged, re-encoded (holes, vbase, _wide) and written in place when the working revision''s, else closed and inserted anew (emptied: deleted or closed); returns the chunks written';
