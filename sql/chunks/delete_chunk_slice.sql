-- tgsis.delete_chunk_slice(table, geoid, times): delete every row of one instant (or period) of an object from a model table stored in chunks, set-based, for the calling role.
-- tgsis.delete_instant and tgsis.delete_period remove a whole slice of an
-- object: model 2's times_vrtx / times_trgl rows of (geoid, times), model 3's
-- d4dvrtx / d4dtrgl rows of (geoid, timem). Through the face a DELETE
-- rewrites a chunk per row (tgsis.chunk_face_write); here the slice's chunk
-- versions go whole, in one statement: those written in the working revision
-- W are deleted, the others closed (W appended to lastrevs), as
-- tgsis.write_chunk_rows does with a chunk left without a present slot. The
-- versions and what every version sees afterwards are the face's (the same
-- rows gone). p_times: the values of the chunk key's columns after the
-- object key, as many as the slice fixes (one: times, or timem of d4dvrtx's
-- (timem, timet)), compared as the rows' primary key compares them (float8
-- =: -0.0 is 0.0), as the DELETE it replaces did.
-- The checks of a DELETE through the face, for the whole slice: DELETE on the
-- face (42501), the class's right to delete the feature's rows
-- (tgsis.check_class_write 'UPDATE, DELETE'), the version's write right and
-- TG301 while an older revision is viewed (tgsis.write_revision), TG305 for
-- unversioned storage outside DEFAULT's working revision, revision 0 for the
-- features of classes without versioning, the object not locked by another
-- version (TG303); a snapshot older than the chunk table's file is 40001
-- (tgsis.chunk_snapshot_guard, the face's statement check). The object's
-- write lock is taken exclusively (tgsis.object_write_lock: no face writer of
-- it in flight), then the visible versions are locked in key order, again
-- until every visible one is locked (READ COMMITTED: a writer waited for
-- committed a new version, which the next statement sees); under REPEATABLE
-- READ or SERIALIZABLE a version changed after the snapshot fails the lock
-- with 40001, as PostgreSQL's tables answer. The object is noted as changed
-- in the working revision (not for revision 0). Returns the number of chunk
-- versions deleted or closed. SECURITY DEFINER (roles may not update chunk
-- versions): internal, called by delete_instant and delete_period with the
-- caller's rights, so executable by tgsis_reader (every tgsis role).
CREATE FUNCTION tgsis.delete_chunk_slice(p_table text, p_geoid bigint, p_times double precision[])
RETURNS bigint
LANGUAGE plpgsql
VOLATILE
SECURITY DEFINER
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_reg       tgsis.model_tables;
    v_face      regclass;
    v_chunk     regclass;
    v_keys      text[];
    v_versioned boolean;
    v_w         integer;
    v_set       integer[];
    v_match     text;
    v_vis       text := '(c.revision = ANY ($1)) IS TRUE AND NOT (c.lastrevs && $1)';
    v_locked    text[] := '{}';
    v_new       text[];
    v_more      boolean;
    v_done      bigint;
BEGIN
    SELECT * INTO v_reg FROM tgsis.model_tables t WHERE t.tablename = p_table AND t.chunkcolumn IS NOT NULL;
    IF NOT FOUND OR NOT tgsis.stored_in_chunks(p_table) THEN
        RAISE EXCEPTION 'tgsis.% is not stored in chunks', coalesce(quote_ident(p_table), 'NULL')
            USING ERRCODE = 'TG100',
                  DETAIL = 'tgsis.delete_chunk_slice deletes from the model tables switched to chunks (tgsis.stored_in_chunks).',
                  HINT = 'delete the rows of a table stored as rows through its view';
    END IF;
    -- first, what the face's statement trigger checks first: a snapshot older than the chunk table (older than
    -- the catalog rows that tgsis.chunk_table_of and chunk_key read, too) is 40001
    PERFORM tgsis.chunk_snapshot_guard(to_regclass(format('tgsis.%I', p_table || '_chunk')));
    v_chunk := tgsis.chunk_table_of(p_table);
    v_keys := tgsis.chunk_key(p_table);  -- {geoid, times}, {geoid, timem, timet}, ...
    IF p_geoid IS NULL OR p_times IS NULL OR array_position(p_times, NULL) IS NOT NULL
       OR cardinality(p_times) = 0 OR cardinality(p_times) >= cardinality(v_keys)
       OR v_keys[1] <> v_reg.keycolumn THEN
        RAISE EXCEPTION 'cannot delete a slice of tgsis.%: the object and % of its key values are needed',
                        quote_ident(p_table), cardinality(v_keys) - 1
            USING ERRCODE = 'TG100',
                  DETAIL = format('The chunk key is (%s); given %s and %s.', array_to_string(v_keys, ', '),
                                  coalesce(p_geoid::text, 'NULL'), coalesce(p_times::text, 'NULL')),
                  HINT = 'give the object key and the time values after it, none NULL';
    END IF;
    v_face := format('tgsis.%I', p_table)::regclass;
    -- the checks of a DELETE through the face (tgsis.chunk_face_write)
    IF NOT has_table_privilege(tgsis.calling_role(), v_face, 'DELETE') THEN
        RAISE EXCEPTION 'permission denied for view %', p_table
            USING ERRCODE = 'insufficient_privilege', DETAIL = format('Deleting rows of %s needs DELETE on it.', v_face),
                  HINT = 'its owner can GRANT DELETE on it';
    END IF;
    PERFORM tgsis.check_class_write(ARRAY[p_geoid], 'UPDATE, DELETE');
    v_versioned := EXISTS (SELECT FROM tgsis.versioned_tables t WHERE t.schemaname = 'tgsis' AND t.tablename = p_table);
    IF v_versioned THEN
        SELECT w.revision, w.revisions INTO v_w, v_set FROM tgsis.write_revision() AS w;  -- TG002, TG301
        IF v_reg.objectclass = 'feature' AND EXISTS (SELECT FROM tgsis.unversioned_features u WHERE u.geoid = p_geoid) THEN
            v_w := tgsis.unversioned_revision(ARRAY[p_geoid]);  -- TG305, TG300
            v_set := ARRAY[0];
        END IF;
        PERFORM tgsis.check_objects_unlocked(v_reg.objectclass, ARRAY[p_geoid::text]);
    ELSE
        PERFORM tgsis.plain_write_check('tgsis', p_table);  -- TG305
        v_w := 0;
        v_set := ARRAY[0];
    END IF;
    PERFORM tgsis.object_write_lock(v_reg.objectclass, ARRAY[p_geoid::text]);

    -- the slice's visible chunk versions: the object's, the given key values ($3, $4), seen by the set ($1)
    v_match := format('c.%I = $3', v_keys[1]) || (SELECT string_agg(format(' AND c.%I = $4[%s]', v_keys[o + 1], o), '' ORDER BY o)
                                                    FROM generate_series(1, cardinality(p_times)) AS o);
    -- locked in key order, until every visible one is (READ COMMITTED: what a writer waited for committed)
    LOOP
        EXECUTE format('SELECT coalesce(array_agg(l.t), ''{}'') FROM (
                          SELECT c.tableoid::text || '':'' || c.ctid::text AS t FROM %1$s c
                           WHERE %2$s AND %3$s AND c.tableoid::text || '':'' || c.ctid::text <> ALL ($5)
                           ORDER BY %4$s FOR UPDATE OF c) l',
                       v_chunk, v_match, v_vis,
                       array_to_string(ARRAY(SELECT format('c.%I', k) FROM unnest(v_keys || 'chunk'::text) AS k), ', '))
           INTO v_new USING v_set, v_w, p_geoid, p_times, v_locked;
        v_locked := v_locked || v_new;
        EXECUTE format('SELECT EXISTS (SELECT FROM %1$s c WHERE %2$s AND %3$s AND c.tableoid::text || '':'' || c.ctid::text <> ALL ($5))',
                       v_chunk, v_match, v_vis)
           INTO v_more USING v_set, v_w, p_geoid, p_times, v_locked;
        EXIT WHEN NOT v_more;
    END LOOP;
    -- W's own versions deleted, the others closed in W: one statement
    EXECUTE format('WITH d AS (DELETE FROM %1$s c WHERE %2$s AND %3$s AND c.revision = $2 RETURNING 1),
                         u AS (UPDATE %1$s c SET lastrevs = c.lastrevs || $2 WHERE %2$s AND %3$s AND c.revision <> $2 RETURNING 1)
                    SELECT (SELECT count(*) FROM d) + (SELECT count(*) FROM u)',
                   v_chunk, v_match, v_vis)
       INTO v_done USING v_set, v_w, p_geoid, p_times;
    IF v_done > 0 AND v_versioned AND v_w <> 0 THEN
        PERFORM tgsis.record_changed_objects('tgsis', p_table, ARRAY[p_geoid::text]);
    END IF;
    RETURN v_done;
END
$$;

REVOKE ALL ON FUNCTION tgsis.delete_chunk_slice(text, bigint, double precision[]) FROM PUBLIC;
GRANT EXECUTE ON FUNCTION tgsis.delete_chunk_slice(text, bigint, double precision[]) TO tgsis_reader;

COMMENT ON FUNCTION tgsis.delete_chunk_slice(text, bigint, double precision[]) IS
    'delete every row of one instant or period of an object (the chunk key''s values after the object key) from a model table stored in chunks, for the calling role, set-based: the checks of a DELETE through the face, the object''s write lock, the visible chunk versions locked in key order, then deleted (the working revision''s) or closed; returns the chunk versions deleted or closed';
