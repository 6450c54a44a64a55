-- tgsis.vertex(geoid, vrtxid): one vertex of an object by its key, read by key from the chunks (docs/storage.md, "The relational face").
-- Once model 1 is stored in chunks, the view tgsis.vrtx cannot find one vertex
-- by its key through an index (the key is computed from the chunk number and
-- the slot): a query "WHERE geoid = g AND vrtxid = k" on it unnests the
-- object. This function reads the one chunk k >> log2(chunksize) by the chunk
-- table's primary key and takes its slot: the psql user's keyed read. Until
-- the storage switch creates tgsis.vrtx_chunk as model 1's storage, it reads
-- today's rows (tgsis.vrtx) by their key. The session's visibility: the
-- viewing set (tgsis.get_revisions(true)) when the storage is versioned,
-- every chunk (revision 0) when not. SECURITY INVOKER: the caller's grants
-- and the chunk table's row-level security (a role without the class's
-- SELECT right sees no row), as on tgsis.vrtx. No row for an absent vertex.
CREATE FUNCTION tgsis.vertex(p_geoid bigint, p_vrtxid bigint)
RETURNS TABLE (x double precision, y double precision, z double precision)
LANGUAGE plpgsql
STABLE
PARALLEL SAFE
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_size bigint;
    v_set  integer[];
BEGIN
    IF to_regclass('tgsis.vrtx_chunk') IS NULL THEN
        RETURN QUERY SELECT v.x, v.y, v.z FROM tgsis.vrtx v WHERE v.geoid = p_geoid AND v.vrtxid = p_vrtxid;
        RETURN;
    END IF;
    SELECT t.chunksize INTO v_size FROM tgsis.model_tables t WHERE t.tablename = 'vrtx';
    IF EXISTS (SELECT FROM tgsis.versioned_tables t WHERE t.schemaname = 'tgsis' AND t.tablename = 'vrtx') THEN
        v_set := tgsis.get_revisions(true);
    END IF;
    RETURN QUERY
    SELECT c.x[s.slot], c.y[s.slot], c.z[s.slot]
      FROM tgsis.vrtx_chunk c, (SELECT ((p_vrtxid % v_size) + 1)::integer AS slot) s
     WHERE c.geoid = p_geoid AND c.chunk = p_vrtxid / v_size AND p_vrtxid >= 0
       AND (v_set IS NULL OR ((c.revision = ANY (v_set)) IS TRUE AND (NOT c.revclosed OR NOT (c.lastrevs && v_set))))
       AND c.x[s.slot] IS NOT NULL;
END
$$;

COMMENT ON FUNCTION tgsis.vertex(bigint, bigint) IS
    'one vertex (x, y, z) of object p_geoid by its id, read from the one chunk holding it (tgsis.vrtx_chunk, the session''s visible version; today''s rows of tgsis.vrtx until model 1 is stored in chunks); no row when absent; the caller''s rights apply';
