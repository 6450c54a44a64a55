-- tgsis.gmap_side_gap(geoid, from period and instant, to period and instant, tolerance): how far the points of one shape of a model-4 G-map lie from another shape's edges.
-- One side of the continuity check of a topology change of a G-map
-- (tgsis.period_gaps): for every node (point of a 0-cell) of the "from"
-- shape, its distance in R^m to the nearest edge or point of the "to" shape
-- (tgsis.gmap_edges_at); returns the largest, its node, and whether it is
-- exact. Edges, not faces: the faces of an n-G-map are polygons that need
-- not be planar, where "lying on the face" has no single meaning.
-- Candidates come from a uniform grid over the first three coordinates as
-- in tgsis.surface_side_gap; points farther than the tolerance are measured against
-- every edge, at most 2,000,000 point-edge pairs (beyond: exact is false,
-- the gap is at least the value returned).
CREATE FUNCTION tgsis.gmap_side_gap(p_geoid bigint, p_from_timem double precision, p_from_timet double precision,
                                    p_to_timem double precision, p_to_timet double precision,
                                    p_tolerance double precision)
RETURNS TABLE (gap double precision, nodeid bigint, exact boolean)
LANGUAGE plpgsql
STABLE
SET search_path FROM CURRENT
SET enable_nestloop = off  -- rows just written have no statistics: a nested loop over the grid costs n x cells
SET jit = off  -- a disabled plan node costs 1e10 on PostgreSQL < 18: JIT would compile (0.6 s a call) what runs in ms
AS $$
#variable_conflict use_column
DECLARE
    v_cell   double precision;
    v_nseg   bigint;
    v_far    bigint[];
    v_limit  bigint;
    v_gap    double precision;
    v_node   bigint;
    v_gap2   double precision;
    v_node2  bigint;
BEGIN
    SELECT count(*),
           avg(greatest(abs(coalesce(s.a[1], 0) - coalesce(s.b[1], 0)), abs(coalesce(s.a[2], 0) - coalesce(s.b[2], 0)),
                        abs(coalesce(s.a[3], 0) - coalesce(s.b[3], 0)))) FILTER (WHERE s.node1 <> s.node2),
           1e-3 * greatest(max(coalesce(s.a[1], 0)) - min(coalesce(s.a[1], 0)), max(coalesce(s.a[2], 0)) - min(coalesce(s.a[2], 0)),
                           max(coalesce(s.a[3], 0)) - min(coalesce(s.a[3], 0)))
      INTO v_nseg, v_cell, v_gap
      FROM tgsis.gmap_edges_at(p_geoid, p_to_timem, p_to_timet) s;
    IF v_nseg = 0 THEN
        RETURN;  -- nothing to measure against (tgsis.check_gmap_geometry reports missing positions)
    END IF;
    v_cell := greatest(v_cell, p_tolerance, v_gap);
    IF NOT v_cell > 0 OR v_cell = 'Infinity' THEN
        v_cell := 1;  -- every point at one place: any cell finds them
    END IF;

    WITH grid AS MATERIALIZED (
        SELECT s.a, s.b, e.i0 + i AS i, e.j0 + j AS j, e.k0 + k AS k
          FROM tgsis.gmap_edges_at(p_geoid, p_to_timem, p_to_timet) s,
               LATERAL (SELECT floor((least(coalesce(s.a[1], 0), coalesce(s.b[1], 0)) - p_tolerance) / v_cell) AS i0,
                               floor((greatest(coalesce(s.a[1], 0), coalesce(s.b[1], 0)) + p_tolerance) / v_cell) AS i1,
                               floor((least(coalesce(s.a[2], 0), coalesce(s.b[2], 0)) - p_tolerance) / v_cell) AS j0,
                               floor((greatest(coalesce(s.a[2], 0), coalesce(s.b[2], 0)) + p_tolerance) / v_cell) AS j1,
                               floor((least(coalesce(s.a[3], 0), coalesce(s.b[3], 0)) - p_tolerance) / v_cell) AS k0,
                               floor((greatest(coalesce(s.a[3], 0), coalesce(s.b[3], 0)) + p_tolerance) / v_cell) AS k1) e,
               generate_series(0, (e.i1 - e.i0)::int) i, generate_series(0, (e.j1 - e.j0)::int) j,
               generate_series(0, (e.k1 - e.k0)::int) k),
    near AS (
        SELECT p.nodeid, min(tgsis.point_segment_distance(p.coordinate, g.a, g.b)) AS d
          FROM tgsis.gmap_vertex p
          LEFT JOIN grid g ON g.i = floor(coalesce(p.coordinate[1], 0) / v_cell) AND g.j = floor(coalesce(p.coordinate[2], 0) / v_cell)
                          AND g.k = floor(coalesce(p.coordinate[3], 0) / v_cell)
         WHERE p.geoid = p_geoid AND p.timem = p_from_timem AND p.timet = p_from_timet
           AND NOT EXISTS (SELECT FROM unnest(p.coordinate) c WHERE c IN ('NaN', 'Infinity', '-Infinity'))
         GROUP BY p.nodeid)
    SELECT max(n.d) FILTER (WHERE n.d <= p_tolerance),
           (array_agg(n.nodeid ORDER BY n.d DESC) FILTER (WHERE n.d <= p_tolerance))[1],
           array_agg(n.nodeid ORDER BY n.nodeid) FILTER (WHERE n.d IS NULL OR n.d > p_tolerance)
      INTO v_gap, v_node, v_far
      FROM near n;

    exact := true;
    IF v_far IS NOT NULL THEN
        -- points farther than the tolerance from every candidate: measured against all the edges
        v_limit := greatest(1, 2000000 / v_nseg);
        IF cardinality(v_far) > v_limit THEN
            v_far := v_far[1:v_limit];
            exact := false;
        END IF;
        SELECT f.d, f.nodeid INTO v_gap2, v_node2
          FROM (SELECT p.nodeid, min(tgsis.point_segment_distance(p.coordinate, s.a, s.b)) AS d
                  FROM tgsis.gmap_vertex p
                  CROSS JOIN tgsis.gmap_edges_at(p_geoid, p_to_timem, p_to_timet) s
                 WHERE p.geoid = p_geoid AND p.timem = p_from_timem AND p.timet = p_from_timet AND p.nodeid = ANY (v_far)
                 GROUP BY p.nodeid) f
         ORDER BY f.d DESC, f.nodeid
         LIMIT 1;
        IF v_gap IS NULL OR v_gap2 > v_gap THEN
            v_gap := v_gap2;
            v_node := v_node2;
        END IF;
    END IF;
    gap := v_gap;
    nodeid := v_node;
    IF gap IS NOT NULL THEN
        RETURN NEXT;
    END IF;
END
$$;

COMMENT ON FUNCTION tgsis.gmap_side_gap(bigint, double precision, double precision, double precision, double precision,
                                        double precision) IS
    'model 4: the largest distance in R^m from a point of the shape at (from period, instant) to the edges and points of the shape at (to period, instant), its node, and whether it is exact; one side of tgsis.period_gaps';
