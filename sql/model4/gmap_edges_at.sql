-- tgsis.gmap_edges_at(geoid, timem, timet): the edges of a model-4 G-map's period as segments between their points at one geometry instant.
-- An edge is a 1-cell: the segment between the point of a dart and the
-- point of its alpha_0 image, once per pair of nodes; every node of the
-- period is also returned as a segment of length 0 from itself to itself,
-- so that isolated points (a 0-G-map) count. Edges with a non-finite
-- point are left out (tgsis.check_gmap_geometry reports them). Used by
-- tgsis.gmap_side_gap.
CREATE FUNCTION tgsis.gmap_edges_at(p_geoid bigint, p_timem double precision, p_timet double precision)
RETURNS TABLE (node1 bigint, node2 bigint, a double precision[], b double precision[])
LANGUAGE plpgsql
STABLE
SET search_path FROM CURRENT
AS $$
BEGIN
    RETURN QUERY
    WITH seg AS (
        SELECT least(d.nodeid, e.nodeid) AS n1, greatest(d.nodeid, e.nodeid) AS n2
          FROM tgsis.gmap_dart d
          JOIN tgsis.gmap_alpha l ON l.geoid = p_geoid AND l.dartid = d.dartid AND l.level = 0
          JOIN tgsis.gmap_dart e ON e.geoid = p_geoid AND e.dartid = l.dartid2
         WHERE d.geoid = p_geoid AND d.timem = p_timem
        UNION
        SELECT n.nodeid, n.nodeid FROM tgsis.gmap_node n WHERE n.geoid = p_geoid AND n.timem = p_timem)
    SELECT s.n1, s.n2, v1.coordinate, v2.coordinate
      FROM seg s
      JOIN tgsis.gmap_vertex v1 ON v1.geoid = p_geoid AND v1.timem = p_timem AND v1.timet = p_timet AND v1.nodeid = s.n1
      JOIN tgsis.gmap_vertex v2 ON v2.geoid = p_geoid AND v2.timem = p_timem AND v2.timet = p_timet AND v2.nodeid = s.n2
     WHERE NOT EXISTS (SELECT FROM unnest(v1.coordinate || v2.coordinate) c WHERE c IN ('NaN', 'Infinity', '-Infinity'));
END
$$;

COMMENT ON FUNCTION tgsis.gmap_edges_at(bigint, double precision, double precision) IS
    'model 4: the edges (1-cells) of a topology period as segments between their points at a geometry instant, plus every node as a segment of length 0; used by tgsis.gmap_side_gap';
