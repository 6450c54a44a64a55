-- tgsis.vertices(geoid, ids): vertices of an object by their keys, in the order of the ids, read by key from the chunks.
-- The set form of tgsis.vertex (which says why it exists): each id's chunk is
-- read by the chunk table's primary key (one probe per distinct chunk the
-- planner's nested loop visits), its slot taken. Rows come in the order of
-- p_ids (an id given twice comes twice); an absent id gives no row. Until
-- the storage switch makes tgsis.vrtx_chunk the storage
-- (tgsis.stored_in_chunks: not merely once the chunk table exists, which
-- tgsis.rows_to_chunks fills while the rows stay the storage) it reads
-- today's rows (tgsis.vrtx); so does a role that may read the face
-- tgsis.vrtx but not the chunk table (correct, at the cost of a scan of
-- the object). Visibility and rights as tgsis.vertex.
-- The visibility test below is tgsis.visible_versions' text, kept static (tests/test_visible_versions.py compares).
CREATE FUNCTION tgsis.vertices(p_geoid bigint, p_ids bigint[])
RETURNS TABLE (vrtxid bigint, x double precision, y double precision, z double precision)
LANGUAGE plpgsql
STABLE
PARALLEL SAFE
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_size bigint;
    v_set  integer[];
BEGIN
    IF NOT tgsis.stored_in_chunks('vrtx') OR NOT has_table_privilege('tgsis.vrtx_chunk', 'SELECT') THEN
        -- rows; or a role granted the face but not the chunk table: through the face (a scan of the object)
        RETURN QUERY
        SELECT u.id, v.x, v.y, v.z
          FROM unnest(p_ids) WITH ORDINALITY AS u(id, o) JOIN tgsis.vrtx v ON v.geoid = p_geoid AND v.vrtxid = u.id
         ORDER BY u.o;
        RETURN;
    END IF;
    SELECT t.chunksize INTO v_size FROM tgsis.model_tables t WHERE t.tablename = 'vrtx';
    IF EXISTS (SELECT FROM tgsis.versioned_tables t WHERE t.schemaname = 'tgsis' AND t.tablename = 'vrtx') THEN
        v_set := tgsis.get_revisions(true);
    END IF;
    RETURN QUERY
    SELECT u.id, c.x[u.slot], c.y[u.slot], c.z[u.slot]
      FROM (SELECT i.id, i.o, i.id / v_size AS chunk, ((i.id % v_size) + 1)::integer AS slot
              FROM unnest(p_ids) WITH ORDINALITY AS i(id, o) WHERE i.id >= 0) u
      JOIN tgsis.vrtx_chunk c ON c.geoid = p_geoid AND c.chunk = u.chunk
     WHERE (v_set IS NULL OR ((c.revision = ANY (v_set)) IS TRUE AND (NOT c.revclosed OR NOT (c.lastrevs && v_set))))
       AND c.x[u.slot] IS NOT NULL
     ORDER BY u.o;
END
$$;

COMMENT ON FUNCTION tgsis.vertices(bigint, bigint[]) IS
    'vertices (vrtxid, x, y, z) of object p_geoid by their ids, in the order of p_ids (absent ids: no row), each read from its chunk by key (tgsis.vrtx_chunk, the session''s visible versions; today''s rows of tgsis.vrtx until tgsis.stored_in_chunks(''vrtx'')); the caller''s rights apply';
