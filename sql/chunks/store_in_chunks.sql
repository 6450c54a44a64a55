-- tgsis.store_in_chunks(table): the storage switch of one model table, from rows to chunks behind a face with today's name.
-- docs/storage.md, "The relational face: views with today's names" and
-- "Upgrading an existing database": in one transaction,
-- 1. tgsis.<table>_chunk and its decoded view are created and filled from the
--    row storage (tgsis.rows_to_chunks, which verifies every version's and
--    every revision's set before returning: TG000 and nothing changed on a
--    difference);
-- 2. the row table's definition (columns, NOT NULLs, CHECKs, primary key and
--    comments; not the versioning columns) is kept, without rows, as
--    tgsis.<table>_shape: the marker tgsis.stored_in_chunks reads and the
--    definition tgsis.row_shape gives the layer's functions (a CHECK that is
--    always false keeps it empty);
-- 3. the face tgsis.<table> is made (tgsis.create_chunk_face) with the grants
--    of the relation it replaces, and the row storage is dropped: the table,
--    or the versioned view, its <table>_ver, write queue, write function and
--    runner. A versioned table stays registered (tgsis.versioned_tables): the
--    chunk table is its storage (tgsis.storage_table), guarded as <table>_ver
--    was (tgsis.guard_chunk_storage), the face decides visibility at each read;
-- 4. the conflicts solved before keep their solutions and regions: their marks
--    (fingerprints of the stored versions) are renewed (tgsis.conflict_marks,
--    tgsis.renew_conflict_marks).
-- Views of the users' own over the table block the drop (PostgreSQL names
-- them, nothing changes). Partitioned storage (tgsis.partition_model_storage)
-- gives a chunk table partitioned the same way (tgsis.partition_chunk_storage).
-- Refused by name: a table not registered for chunks (TG200), one stored in
-- chunks already (TG201), storage partitioned another way (TG100), a table
-- of points (role 'point': a G-map's vertices) holding an object whose points
-- are not all of one length, or one without coordinates (TG100 naming the
-- object and the point, before anything is made). Returns the chunk versions
-- written. Internal (tgsis's owner: it creates and drops the storage).
CREATE FUNCTION tgsis.store_in_chunks(p_table text)
RETURNS bigint
LANGUAGE plpgsql
VOLATILE
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_storage   regclass;
    v_shape     text := p_table || '_shape';
    v_versioned tgsis.versioned_tables;
    v_keys      text[];
    v_pkey      text;
    v_n         bigint;
    v_name      text;
    v_marks     jsonb;
    v_parts     integer;
BEGIN
    PERFORM FROM tgsis.chunk_columns(p_table);  -- TG200 not registered for chunks, TG100 does not fit
    IF tgsis.stored_in_chunks(p_table) THEN
        RAISE EXCEPTION 'tgsis.% is stored in chunks already', quote_ident(p_table)
            USING ERRCODE = 'TG201', DETAIL = format('Its chunk table is tgsis.%I.', p_table || '_chunk');
    END IF;
    IF to_regclass(format('tgsis.%I', v_shape)) IS NOT NULL OR to_regclass(format('tgsis.%I', p_table || '_face')) IS NOT NULL THEN
        RAISE EXCEPTION 'tgsis.% or tgsis.% exists already', quote_ident(v_shape), quote_ident(p_table || '_face')
            USING ERRCODE = 'TG201', DETAIL = 'The storage switch needs these names for the row definition and the new face.';
    END IF;
    v_storage := tgsis.storage_table('tgsis', p_table)::regclass;
    -- a DBA's index on the row versions' revision columns cannot be kept: refused by name (TG202), nothing changed
    PERFORM tgsis.unkept_indexes_check(v_storage, false, format('tgsis.store_in_chunks(%L)', p_table));
    -- partitioned storage (tgsis.partition_model_storage: HASH (geoid), N partitions of modulus N): the chunk
    -- table is partitioned the same way once filled (tgsis.partition_chunk_storage); another scheme is refused
    IF (SELECT c.relkind FROM pg_class c WHERE c.oid = v_storage) = 'p' THEN
        v_parts := (SELECT count(*) FROM pg_inherits i WHERE i.inhparent = v_storage);
        IF NOT EXISTS (SELECT FROM pg_partitioned_table pt JOIN pg_attribute a ON a.attrelid = pt.partrelid AND a.attnum = pt.partattrs[0]
                        WHERE pt.partrelid = v_storage AND pt.partstrat = 'h' AND pt.partnatts = 1 AND a.attname = 'geoid')
           OR v_parts NOT BETWEEN 2 AND 1024
           OR EXISTS (SELECT FROM pg_inherits i JOIN pg_class c ON c.oid = i.inhrelid
                       WHERE i.inhparent = v_storage
                         AND (c.relkind <> 'r' OR pg_get_expr(c.relpartbound, c.oid) NOT LIKE format('FOR VALUES WITH (modulus %s,%%', v_parts))) THEN
            RAISE EXCEPTION '% is partitioned otherwise than by tgsis.partition_model_storage, which its chunks would not be', v_storage
                USING ERRCODE = 'TG100',
                      DETAIL = 'A chunk table is partitioned as tgsis.partition_model_storage partitions: by HASH (geoid), N partitions of modulus N.',
                      HINT = 'keep this table stored as rows';
        END IF;
    END IF;
    SELECT * INTO v_versioned FROM tgsis.versioned_tables t WHERE t.schemaname = 'tgsis' AND t.tablename = p_table;
    -- a point (role 'point': a G-map's vertex) is a row of its chunk's 2-D array, m per chunk: an object's points
    -- of more than one length (which the row table allows and tgsis.check_geometry reports), or of none, have no
    -- chunk form; refused by name before anything is made or moved (the aggregate would fail 2202E)
    FOR v_name IN SELECT c.name FROM tgsis.chunk_columns(p_table) c WHERE c.role = 'point' ORDER BY c.colorder LOOP
        EXECUTE format(
            'SELECT format(%1$L, r.%2$I, concat_ws(%3$L, %4$s), coalesce(cardinality(r.%5$I), 0), b.len, b.lens)
               FROM %6$s r
               JOIN (SELECT s.%2$I AS k, mode() WITHIN GROUP (ORDER BY coalesce(cardinality(s.%5$I), 0)) AS len,
                            array_agg(DISTINCT coalesce(cardinality(s.%5$I), 0) ORDER BY coalesce(cardinality(s.%5$I), 0)) AS lens
                       FROM %6$s s GROUP BY s.%2$I
                     HAVING count(DISTINCT coalesce(cardinality(s.%5$I), 0)) > 1 OR min(coalesce(cardinality(s.%5$I), 0)) = 0) b
                 ON b.k = r.%2$I
              WHERE coalesce(cardinality(r.%5$I), 0) = 0 OR coalesce(cardinality(r.%5$I), 0) <> b.len
              ORDER BY %7$s LIMIT 1',
            'object %s: the point (%s) has %s coordinates, most of its others %s (lengths %s)',
            (SELECT r.keycolumn FROM tgsis.model_tables r WHERE r.tablename = p_table), ', ',
            (SELECT string_agg(format('r.%I', k), ', ' ORDER BY o)
               FROM unnest(tgsis.chunk_key(p_table) || (SELECT r.chunkcolumn FROM tgsis.model_tables r WHERE r.tablename = p_table))
                    WITH ORDINALITY AS u(k, o)),
            v_name, v_storage,
            (SELECT string_agg(format('r.%I', k), ', ' ORDER BY o)
               FROM unnest(tgsis.chunk_key(p_table) || (SELECT r.chunkcolumn FROM tgsis.model_tables r WHERE r.tablename = p_table))
                    WITH ORDINALITY AS u(k, o)))
           INTO v_pkey;
        IF v_pkey IS NOT NULL THEN
            RAISE EXCEPTION 'tgsis.% cannot be stored in chunks: the points of an object are not all of one length', quote_ident(p_table)
                USING ERRCODE = 'TG100',
                      DETAIL = format('%s, in column %I; a chunk holds one object''s points as the rows of a 2-D array of '
                                      'its embedding''s length, m coordinates each (tgsis.check_geometry reports such '
                                      'objects); nothing was changed.', v_pkey, v_name),
                      HINT = 'give every point of the object its embedding''s m coordinates, then store the table in chunks';
        END IF;
    END LOOP;

    -- the conflicts' marks fingerprint the stored versions, which the switch changes without changing what any
    -- version sees: read before, renewed after (tgsis.renew_conflict_marks), solved conflicts stay solved
    v_marks := tgsis.conflict_marks();

    -- 1. the chunks, verified against every set
    PERFORM tgsis.create_chunk_table(p_table);
    PERFORM tgsis.create_chunk_view(p_table);
    v_n := tgsis.rows_to_chunks(p_table);

    -- 2. the row definition, without rows
    IF v_versioned.tablename IS NOT NULL THEN
        v_keys := v_versioned.keycolumns;
        v_pkey := v_versioned.pkeyname;
    ELSE
        SELECT con.conname, array_agg(a.attname::text ORDER BY k.ord) INTO v_pkey, v_keys
          FROM pg_constraint con
         CROSS JOIN LATERAL unnest(con.conkey) WITH ORDINALITY AS k(attnum, ord)
          JOIN pg_attribute a ON a.attrelid = con.conrelid AND a.attnum = k.attnum
         WHERE con.conrelid = v_storage AND con.contype = 'p'
         GROUP BY con.conname;
    END IF;
    EXECUTE format('CREATE TABLE tgsis.%I (LIKE %s INCLUDING CONSTRAINTS INCLUDING COMMENTS)', v_shape, v_storage);
    IF v_versioned.tablename IS NOT NULL THEN
        EXECUTE format('ALTER TABLE tgsis.%I DROP COLUMN revision, DROP COLUMN lastrevs, DROP COLUMN revclosed', v_shape);
    END IF;
    EXECUTE format('ALTER TABLE tgsis.%I ADD CONSTRAINT %I PRIMARY KEY (%s)', v_shape, v_shape || '_pkey',
                   (SELECT string_agg(quote_ident(k), ', ' ORDER BY o) FROM unnest(v_keys) WITH ORDINALITY AS u(k, o)));
    EXECUTE format('ALTER TABLE tgsis.%I ADD CONSTRAINT %I CHECK (false)', v_shape, p_table || '_shape_holds_no_rows');
    -- no REVOKE: a new table's default rights are its owner's alone, and an explicit ACL saying the same would not
    -- come back from pg_dump (which leaves out an ACL equal to the default): a restore would differ
    -- the row table's own comment first: the face's comment starts with it (tgsis.create_chunk_face)
    EXECUTE format('COMMENT ON TABLE tgsis.%I IS %L', v_shape,
                   coalesce(v_versioned.tablecomment, obj_description(v_storage, 'pg_class')));

    -- 3. the face takes the name; the row storage goes
    PERFORM tgsis.create_chunk_face(p_table, p_table || '_face');  -- the grants of today's tgsis.<table>
    EXECUTE format('COMMENT ON TABLE tgsis.%I IS %L', v_shape,
                   format('the row definition of tgsis.%I (columns, key %s, constraints, comments), kept without rows since it is '
                          'stored in chunks (tgsis.%I behind the face tgsis.%I: tgsis.store_in_chunks)',
                          p_table, coalesce(v_pkey, 'none'), p_table || '_chunk', p_table));

    IF v_versioned.tablename IS NOT NULL THEN
        EXECUTE format('DROP VIEW tgsis.%I', p_table);
        EXECUTE format('DROP FUNCTION tgsis.%I()', p_table || '_ver_write');
        EXECUTE format('DROP TABLE tgsis.%I', p_table || '_ver_queue');
        FOR v_name IN SELECT p.oid::regprocedure::text FROM pg_proc p
                       WHERE p.pronamespace = 'tgsis'::regnamespace AND p.proname = p_table || '_ver_run' LOOP
            EXECUTE format('DROP FUNCTION %s', v_name);
        END LOOP;
    END IF;
    -- the row table's own secondary indexes kept on the row definition, by name (the way back makes them again)
    PERFORM tgsis.move_row_indexes(v_storage, format('tgsis.%I', v_shape)::regclass);
    EXECUTE format('DROP TABLE %s', v_storage);
    EXECUTE format('ALTER VIEW tgsis.%I RENAME TO %I', p_table || '_face', p_table);
    IF v_versioned.tablename IS NOT NULL THEN
        PERFORM tgsis.guard_chunk_storage(p_table);  -- the rights, labels and notes <table>_ver's triggers kept
    END IF;
    IF v_parts IS NOT NULL THEN
        PERFORM tgsis.partition_chunk_storage(p_table, v_parts);  -- as the row storage was, verified again
    END IF;
    PERFORM tgsis.renew_conflict_marks(v_marks);
    RETURN v_n;
END
$$;

REVOKE ALL ON FUNCTION tgsis.store_in_chunks(text) FROM PUBLIC;

COMMENT ON FUNCTION tgsis.store_in_chunks(text) IS
    'switch a model table registered for chunks from rows to chunks in one transaction: tgsis.<table>_chunk filled and verified (tgsis.rows_to_chunks), the row definition kept without rows as tgsis.<table>_shape, the row storage dropped and tgsis.<table> made the face over the chunks (tgsis.create_chunk_face, the grants of the relation it replaces); partitioned storage (tgsis.partition_model_storage) gives a chunk table partitioned the same way; returns the chunk versions written; TG201 when stored in chunks already';
