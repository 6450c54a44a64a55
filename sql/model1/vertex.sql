-- tgsis.vertex(geoid, vrtxid): one vertex of an object by its key, read by key from the chunks (docs/storage.md, "The relational face").
-- Once model 1 is stored in chunks, the view tgsis.vrtx cannot find one vertex
-- by its key through an index (the key is computed from the chunk number and
-- the slot): a query "WHERE geoid = g AND vrtxid = k" on it unnests the
-- object. This function reads the one chunk k >> log2(chunksize) by the chunk
-- table's primary key and takes its slot (through tgsis.vertices, its set
-- form): the psql user's keyed read. Until
-- the storage switch creates tgsis.vrtx_chunk as model 1's storage, it reads
-- today's rows (tgsis.vrtx) by their key. The session's visibility: the
-- viewing set (tgsis.get_revisions(true)) when the storage is versioned,
-- every chunk (revision 0) when not. SECURITY INVOKER: the caller's grants
-- and the chunk table's row-level security (a role without the class's
-- SELECT right sees no row), as on tgsis.vrtx. No row for an absent vertex.
CREATE FUNCTION tgsis.vertex(p_geoid bigint, p_vrtxid bigint)
RETURNS TABLE (x double precision, y double precision, z double precision)
LANGUAGE sql
STABLE
PARALLEL SAFE
SET search_path = pg_catalog, pg_temp
AS $$
    -- the one-id case of tgsis.vertices: one implementation of the keyed read (which storage, visibility, slot)
    SELECT v.x, v.y, v.z FROM tgsis.vertices(p_geoid, ARRAY[p_vrtxid]) AS v
$$;

COMMENT ON FUNCTION tgsis.vertex(bigint, bigint) IS
    'one vertex (x, y, z) of object p_geoid by its id, read from the one chunk holding it (tgsis.vrtx_chunk, the session''s visible version; today''s rows of tgsis.vrtx until model 1 is stored in chunks); no row when absent; the caller''s rights apply';
