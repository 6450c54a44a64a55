-- tgsis.gmap_points_at(geoid, t): the points of a G-map's nodes at model time t, interpolated between the bracketing geometry instants.
-- Each coordinate is a + w (b - a) between the positions at t0 and t1 of the
-- period containing t (tgsis.gmap_frame), the formula EvolvingGMap.at uses
-- (equal to the bit); the positions at t0 when t is an instant.
CREATE FUNCTION tgsis.gmap_points_at(p_geoid bigint, p_t double precision)
RETURNS TABLE (nodeid bigint, coordinate double precision[])
LANGUAGE plpgsql
STABLE
SET search_path FROM CURRENT
AS $$
BEGIN
    RETURN QUERY
    SELECT a.nodeid,
           CASE WHEN f.t0 = f.t1 THEN a.coordinate
                ELSE ARRAY(SELECT x + f.w * (y - x) FROM unnest(a.coordinate, b.coordinate) WITH ORDINALITY AS u (x, y, i)
                            ORDER BY u.i) END
      FROM tgsis.gmap_frame(p_geoid, p_t) f
      JOIN tgsis.gmap_vertex a ON a.geoid = p_geoid AND a.timem = f.timem AND a.timet = f.t0
      JOIN tgsis.gmap_vertex b ON b.geoid = p_geoid AND b.timem = f.timem AND b.timet = f.t1 AND b.nodeid = a.nodeid
     ORDER BY a.nodeid;
END
$$;

COMMENT ON FUNCTION tgsis.gmap_points_at(bigint, double precision) IS
    'model 4 snapshot at t: every node of the period containing t with its point interpolated linearly between the bracketing geometry instants, by nodeid; none when the G-map does not exist at t';
