-- tgsis.storage_key(table): the key of a versioned table's stored versions, without revision: the row key, or the chunk key when stored in chunks.
-- tgsis.versioned_tables.keycolumns is the row key (geoid, vrtxid) on both
-- sides of the storage switch (tgsis.store_in_chunks): what the face, the
-- diffs and the conflict reports name rows by. The functions that act on
-- stored versions themselves (copy_object_state's "one version only one
-- side sees" match, the fingerprints of changed objects) key them by what the
-- storage is keyed by: (geoid, chunk) in tgsis.<table>_chunk, whose primary
-- key is (geoid, chunk, revision), the row key in <table>_ver.
CREATE FUNCTION tgsis.storage_key(p_t tgsis.versioned_tables)
RETURNS text[]
LANGUAGE sql
STABLE
SET search_path = pg_catalog, pg_temp
AS $$
    SELECT CASE WHEN tgsis.stored_in_chunks(p_t.schemaname, p_t.tablename)
                THEN ARRAY(SELECT CASE WHEN u.k = m.chunkcolumn THEN 'chunk' ELSE u.k END
                             FROM pg_catalog.unnest(p_t.keycolumns) WITH ORDINALITY AS u(k, o)
                            ORDER BY u.o)
                ELSE p_t.keycolumns END
      -- (a class's property table is chunked by _idx: tgsis.chunk_registry)
      FROM (SELECT CASE WHEN p_t.schemaname = 'tgsis'
                        THEN (SELECT t.chunkcolumn FROM tgsis.model_tables t WHERE t.tablename = p_t.tablename)
                        ELSE '_idx' END AS chunkcolumn) m
$$;

REVOKE ALL ON FUNCTION tgsis.storage_key(tgsis.versioned_tables) FROM PUBLIC;
-- (reached as the calling role by the invoker functions that read storage: diffs, rows_at, conflict reports)
GRANT EXECUTE ON FUNCTION tgsis.storage_key(tgsis.versioned_tables) TO tgsis_reader;

COMMENT ON FUNCTION tgsis.storage_key(tgsis.versioned_tables) IS
    'the key columns of a versioned table''s stored versions, without revision: the row key (keycolumns) for <table>_ver, the chunk key (the local-id column replaced by chunk) for a chunk table (tgsis.<table>_chunk, a class''s <table>_chunk: _idx replaced)';
