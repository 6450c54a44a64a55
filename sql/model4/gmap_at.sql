-- tgsis.gmap_at(geoid, t): the darts of a G-map at model time t, each with its node and its images under alpha_0 .. alpha_n.
-- The snapshot's topology: the darts (with the cell of the property level each is in) of the topology period containing t
-- (tgsis.gmap_frame); none before the first instant, nor after the end
-- unless alive. The points are tgsis.gmap_points_at, the property values
-- tgsis.gmap_property_at (same t, same period).
CREATE FUNCTION tgsis.gmap_at(p_geoid bigint, p_t double precision)
RETURNS TABLE (dartid bigint, nodeid bigint, acellid bigint, alpha bigint[])
LANGUAGE plpgsql
STABLE
SET search_path FROM CURRENT
AS $$
BEGIN
    RETURN QUERY
    SELECT d.dartid, d.nodeid, d.acellid, array_agg(a.dartid2 ORDER BY a.level)
      FROM tgsis.gmap_frame(p_geoid, p_t) f
      JOIN tgsis.gmap_dart d ON d.geoid = p_geoid AND d.timem = f.timem
      JOIN tgsis.gmap_alpha a ON a.geoid = p_geoid AND a.dartid = d.dartid
     GROUP BY d.dartid, d.nodeid, d.acellid
     ORDER BY d.dartid;
END
$$;

COMMENT ON FUNCTION tgsis.gmap_at(bigint, double precision) IS
    'model 4 snapshot at t: the darts of the topology period containing t with their node, their cell of the class''s property level (acellid) and {alpha_0(d), ..., alpha_n(d)}, by dartid; none when the G-map does not exist at t';
