-- tgsis.write_property_chunks(table, chunks): the bulk upload of a class's property chunks, encoded by the client.
-- docs/storage.md, "Property chunks: the contract": a STATIC class's property
-- table stored in chunks (tgsis.store_class_in_chunks) is written through its
-- face alone, row by row through its trigger: correct, but slow for the
-- upload of a whole feature. The Python upload encodes the chunks itself
-- (tgsis._chunks.encode, as the model-1 upload does), COPYs them into a
-- temporary table of its own and passes them here as an array of the chunk
-- table's row type; this function writes them as the chunk table's owner
-- after the checks the face's trigger (tgsis.chunk_face_write) makes for an
-- INSERT, for the whole set at once:
--   * the calling role's INSERT right on the face (42501), the write of plain
--     storage in DEFAULT's working revision only (tgsis.plain_write_check,
--     TG305), object locks (tgsis.check_objects_unlocked), the objects' write
--     locks shared and the chunks' transaction locks (as the face's writers
--     take them: a face writer and this upload of one chunk wait for each
--     other);
--   * the encoding the readers read (tgsis.chunk_encoding_checks: arrays of
--     the chunk's length, NULL at every hole; 23514 as tgsis.chunk_insert_check),
--     one open version of revision 0 per chunk (23514);
--   * new chunks only: a chunk of an object that is there already is refused
--     (TG201; nothing written), as the face refuses a present key (23505).
-- Built for classes whose tables are not versioned (what store_class_in_chunks
-- switches today): a versioned table is refused by name (TG300; write through
-- the face). SECURITY DEFINER: the chunk table is written by its owner only.
-- Returns the chunk rows written.
CREATE FUNCTION tgsis.write_property_chunks(p_table text, p_chunks anyarray)
RETURNS bigint
LANGUAGE plpgsql
VOLATILE
SECURITY DEFINER
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_reg     record;
    v_chunk   regclass;
    v_face    regclass;
    v_role    name := tgsis.calling_role();
    v_keys    text[];
    v_vid     integer;
    v_bad     record;
    v_columns text;
    v_n       bigint;
BEGIN
    SELECT * INTO v_reg FROM tgsis.chunk_registry(p_table) r WHERE r.classname IS NOT NULL;
    v_chunk := CASE WHEN FOUND THEN to_regclass(tgsis.chunk_relation(p_table, '_chunk')) END;
    v_face := CASE WHEN FOUND THEN to_regclass(format('%I.%I', v_reg.schemaname, v_reg.tablename)) END;
    IF v_chunk IS NULL OR v_face IS NULL OR (SELECT c.relkind FROM pg_class c WHERE c.oid = v_face) <> 'v' THEN
        RAISE EXCEPTION 'the properties of % are not stored in chunks', coalesce(p_table, 'NULL')
            USING ERRCODE = 'TG200',
                  DETAIL = 'Only the property table of a STATIC class switched by tgsis.store_class_in_chunks has chunks to upload.',
                  HINT = 'write the rows into the property table';
    END IF;
    IF pg_typeof(p_chunks) <> (SELECT t.typarray FROM pg_type t JOIN pg_class c ON c.reltype = t.oid WHERE c.oid = v_chunk)::regtype THEN
        RAISE EXCEPTION 'the chunks given are %, not an array of %', pg_typeof(p_chunks), v_chunk
            USING ERRCODE = 'TG100', HINT = format('pass array_agg(ROW(...)::%s) of the chunk rows', v_chunk);
    END IF;
    IF NOT has_table_privilege(v_role, v_face, 'INSERT') THEN
        RAISE EXCEPTION 'permission denied for view %', v_face
            USING ERRCODE = 'insufficient_privilege',
                  DETAIL = format('Role %s lacks INSERT on %s, whose rows these chunks hold.', quote_ident(v_role), v_face);
    END IF;
    IF EXISTS (SELECT FROM tgsis.versioned_tables t WHERE t.schemaname = v_reg.schemaname AND t.tablename = v_reg.tablename) THEN
        RAISE EXCEPTION 'the bulk upload of property chunks is not built for the versioned table %', v_face
            USING ERRCODE = 'TG300', HINT = format('insert the rows into %s, which writes them in the working revision', v_face);
    END IF;
    PERFORM tgsis.plain_write_check(v_reg.schemaname, v_reg.tablename);  -- TG305
    EXECUTE format('SELECT array_agg(DISTINCT c.%I::text ORDER BY c.%I::text) FROM unnest($1) c', v_reg.keycolumn, v_reg.keycolumn)
       INTO v_keys USING p_chunks;
    IF v_keys IS NULL THEN
        RETURN 0;
    END IF;

    -- the face's locks: object locks, the objects' write locks shared, the chunks' transaction locks in key order
    IF EXISTS (SELECT FROM tgsis.object_locks l WHERE l.objectclass = 'feature' AND l.objectkey = ANY (v_keys)) THEN
        PERFORM tgsis.check_objects_unlocked('feature', v_keys);
    END IF;
    v_vid := tgsis.version_id(tgsis.get_working_version());
    IF cardinality(v_keys) > tgsis.object_lock_limit() THEN
        PERFORM pg_advisory_xact_lock(tgsis.object_class_lock_key('feature', v_vid));
    ELSE
        PERFORM pg_advisory_xact_lock_shared(tgsis.object_lock_key('feature', k, v_vid)) FROM unnest(v_keys) AS k;
    END IF;
    EXECUTE format('SELECT count(pg_advisory_xact_lock(pg_catalog.hashtextextended(%L || k, $2))) '
                   'FROM (SELECT DISTINCT ROW(c.%I, c.chunk)::text AS k FROM unnest($1) c ORDER BY 1) AS s',
                   'tgsis chunk ' || p_table || ' ', v_reg.keycolumn)
       USING p_chunks, v_vid;

    -- the encoding, and one open version of revision 0 per chunk
    EXECUTE format('SELECT c.%I AS object, c.chunk, count(*) OVER () AS n FROM unnest($1) c '
                   'WHERE NOT coalesce(%s, false) OR c.revision IS DISTINCT FROM 0 OR c.lastrevs IS DISTINCT FROM ''{}'' '
                   'ORDER BY 1, 2 LIMIT 1',
                   v_reg.keycolumn, array_to_string(tgsis.chunk_encoding_checks(p_table), ' AND '))
       INTO v_bad USING p_chunks;
    IF v_bad.chunk IS NOT NULL THEN
        RAISE EXCEPTION 'a chunk of % is not encoded as its readers read it: object %, chunk %', v_chunk, v_bad.object, v_bad.chunk
            USING ERRCODE = 'check_violation',
                  DETAIL = format('%s chunk(s) with arrays not one-dimensional from 1, of unequal length or longer than a chunk, '
                                  'ending on a hole, not NULL at a hole, or not an open version of revision 0; nothing was written '
                                  '(docs/storage.md, "Property chunks: the contract").', v_bad.n),
                  HINT = format('insert the rows into %s, which encodes them', v_face);
    END IF;

    SELECT string_agg(quote_ident(a.attname), ', ' ORDER BY a.attnum) INTO v_columns
      FROM pg_attribute a
     WHERE a.attrelid = v_chunk AND a.attnum > 0 AND NOT a.attisdropped AND a.attgenerated = '';
    BEGIN
        EXECUTE format('INSERT INTO %s (%s) SELECT %s FROM unnest($1) c', v_chunk, v_columns,
                       (SELECT string_agg('c.' || c, ', ') FROM unnest(string_to_array(v_columns, ', ')) AS c))
           USING p_chunks;
        GET DIAGNOSTICS v_n = ROW_COUNT;
    EXCEPTION WHEN unique_violation THEN
        RAISE EXCEPTION 'chunks of % are there already: an upload writes new objects''s chunks only', v_face
            USING ERRCODE = 'TG201', DETAIL = SQLERRM || '; nothing was written',
                  HINT = format('change rows of an object that is there through %s', v_face);
    END;
    RETURN v_n;
END
$$;

REVOKE ALL ON FUNCTION tgsis.write_property_chunks(text, anyarray) FROM PUBLIC;
GRANT EXECUTE ON FUNCTION tgsis.write_property_chunks(text, anyarray) TO tgsis_reader;

COMMENT ON FUNCTION tgsis.write_property_chunks(text, anyarray) IS
    'the bulk upload of a STATIC class''s property chunks encoded by the client (an array of the chunk table''s row type; tgsis.store_class_in_chunks): the calling role''s INSERT on the face (42501), TG305, object locks, the face''s object and chunk locks, the encoding and revision 0 (23514), new chunks only (TG201); TG300 for a versioned table; returns the chunk rows written';
