-- tgsis.check_gmap_geometry(geoid): what is wrong with a stored G-map geometry, in the form tgsis.check_geometry returns.
-- Model 4's check function in the registry (tgsis.data_models): the
-- conditions of tgsis.gmap_check (first offending dart as the example), the
-- positions of every node at every geometry instant of its period with m
-- coordinates, shapes that jump at a topology instant, and the bbox and
-- counts.
CREATE FUNCTION tgsis.check_gmap_geometry(p_geoid bigint)
RETURNS TABLE (problem text, count bigint, example text)
LANGUAGE plpgsql
STABLE
SET search_path FROM CURRENT
AS $$
DECLARE
    v_m smallint;
BEGIN
    IF NOT EXISTS (SELECT FROM tgsis.gmap g WHERE g.geoid = p_geoid) THEN
        RETURN QUERY SELECT 'G-map geometry has no tgsis.gmap row'::text, 1::bigint, p_geoid::text;
        RETURN;
    END IF;
    RETURN QUERY SELECT c.problem, c.count, 'dart ' || c.darts[1] FROM tgsis.gmap_check(p_geoid) c;
    SELECT g.embedding INTO v_m FROM tgsis.gmap g WHERE g.geoid = p_geoid;
    RETURN QUERY
        SELECT format('point without %s finite coordinates', v_m), count(*), 'node ' || min(v.nodeid)
          FROM tgsis.gmap_vertex v
         WHERE v.geoid = p_geoid
           AND (cardinality(v.coordinate) <> v_m
                OR EXISTS (SELECT FROM unnest(v.coordinate) c WHERE c IN ('NaN', 'Infinity', '-Infinity')))
        HAVING count(*) > 0;
    RETURN QUERY
        SELECT 'node without a position at a geometry instant of its period'::text, count(*), 'node ' || min(n.nodeid)
          FROM tgsis.gmap_node n
          JOIN tgsis.gmap_timet t ON t.geoid = n.geoid AND t.timem = n.timem
         WHERE n.geoid = p_geoid
           AND NOT EXISTS (SELECT FROM tgsis.gmap_vertex v WHERE v.geoid = n.geoid AND v.timem = n.timem
                                                            AND v.timet = t.timet AND v.nodeid = n.nodeid)
        HAVING count(*) > 0;
    RETURN QUERY
        SELECT 'shape jumps at a topology instant: the period''s first shape lies farther than the tolerance from the last shape before it (tgsis.period_gaps)'::text,
               count(*), (array_agg(format('period from %s: %s apart at %s', g.timem, g.gap, g.place) ORDER BY g.timem))[1]
          FROM tgsis.period_gaps(p_geoid) g
         WHERE g.gap > g.tolerance
        HAVING count(*) > 0;
    RETURN QUERY
        SELECT 'bounding box or counts out of date (run tgsis.refresh_geometry)'::text, 1::bigint, NULL::text
          FROM tgsis.geometry g, tgsis.gmap_extent(p_geoid) e
         WHERE g.geoid = p_geoid
           AND (g.nvrtx <> e.nvrtx OR g.ncell <> e.ncell OR g.bbox IS DISTINCT FROM e.bbox);
END
$$;

COMMENT ON FUNCTION tgsis.check_gmap_geometry(bigint) IS
    'problems of a stored G-map geometry: those of tgsis.gmap_check, points without m finite coordinates, nodes missing a position at an instant of their period, shapes that jump at a topology instant (tgsis.period_gaps), stale bbox/counts; model 4''s check function (tgsis.data_models)';
