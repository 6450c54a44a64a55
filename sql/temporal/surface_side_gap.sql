-- tgsis.surface_side_gap(geoid, from period and instant, to period and instant, tolerance): how far the nodes of one shape of a model-3 surface lie from another shape's triangles.
-- One side of the continuity check of a topology change (tgsis.period_gaps):
-- for every node of the "from" shape, its distance to the nearest triangle
-- of the "to" shape; returns the largest and its node. Candidates come from a
-- uniform grid (cell = the larger of the tolerance and the mean extent of a
-- triangle): every triangle whose box, grown by the tolerance, meets a node's cell and holds
-- the node is a candidate, so a distance up to the tolerance is exact. Nodes farther (a jump) are measured
-- against every triangle, at most 2,000,000 node-triangle pairs; beyond,
-- the first of them only, and exact is false (the gap is then at least the
-- value returned). Non-finite positions are left out (tgsis.check_temporal_geometry
-- reports them).
CREATE FUNCTION tgsis.surface_side_gap(p_geoid bigint, p_from_timem double precision, p_from_timet double precision,
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
    v_ntri   bigint;
    v_far    bigint[];
    v_limit  bigint;
    v_gap    double precision;
    v_node   bigint;
    v_gap2   double precision;
    v_node2  bigint;
BEGIN
    SELECT count(*), avg(greatest(greatest(a.x, b.x, c.x) - least(a.x, b.x, c.x), greatest(a.y, b.y, c.y) - least(a.y, b.y, c.y),
                                  greatest(a.z, b.z, c.z) - least(a.z, b.z, c.z)))
      INTO v_ntri, v_cell
      FROM tgsis.d4dtrgl t
      JOIN tgsis.d4dvrtx a ON a.geoid = p_geoid AND a.timem = p_to_timem AND a.timet = p_to_timet AND a.nodeid = t.nodeid1
      JOIN tgsis.d4dvrtx b ON b.geoid = p_geoid AND b.timem = p_to_timem AND b.timet = p_to_timet AND b.nodeid = t.nodeid2
      JOIN tgsis.d4dvrtx c ON c.geoid = p_geoid AND c.timem = p_to_timem AND c.timet = p_to_timet AND c.nodeid = t.nodeid3
     WHERE t.geoid = p_geoid AND t.timem = p_to_timem
       AND a.x NOT IN ('NaN', 'Infinity', '-Infinity') AND a.y NOT IN ('NaN', 'Infinity', '-Infinity') AND a.z NOT IN ('NaN', 'Infinity', '-Infinity')
       AND b.x NOT IN ('NaN', 'Infinity', '-Infinity') AND b.y NOT IN ('NaN', 'Infinity', '-Infinity') AND b.z NOT IN ('NaN', 'Infinity', '-Infinity')
       AND c.x NOT IN ('NaN', 'Infinity', '-Infinity') AND c.y NOT IN ('NaN', 'Infinity', '-Infinity') AND c.z NOT IN ('NaN', 'Infinity', '-Infinity');
    IF v_ntri = 0 THEN
        RETURN;  -- no surface to measure against (tgsis.check_temporal_geometry reports missing positions)
    END IF;
    -- the cell: a distance up to it is found in the node's own cell; never so small that a triangle spans
    -- millions of cells (a surface of a few degenerate triangles: its extent over a thousand)
    SELECT greatest(v_cell, p_tolerance,
                    1e-3 * max(greatest(abs(v.x - m.x0), abs(v.y - m.y0), abs(v.z - m.z0))))
      INTO v_cell
      FROM tgsis.d4dvrtx v,
           (SELECT min(w.x) AS x0, min(w.y) AS y0, min(w.z) AS z0 FROM tgsis.d4dvrtx w
             WHERE w.geoid = p_geoid AND w.timem = p_to_timem AND w.timet = p_to_timet
               AND w.x NOT IN ('NaN', 'Infinity', '-Infinity') AND w.y NOT IN ('NaN', 'Infinity', '-Infinity') AND w.z NOT IN ('NaN', 'Infinity', '-Infinity')) m
     WHERE v.geoid = p_geoid AND v.timem = p_to_timem AND v.timet = p_to_timet
       AND v.x NOT IN ('NaN', 'Infinity', '-Infinity') AND v.y NOT IN ('NaN', 'Infinity', '-Infinity') AND v.z NOT IN ('NaN', 'Infinity', '-Infinity');
    IF NOT v_cell > 0 OR v_cell = 'Infinity' THEN
        v_cell := 1;  -- every triangle a point, all at one place: any cell finds them
    END IF;

    WITH tri AS MATERIALIZED (
        SELECT t.trglid, a.x AS xa, a.y AS ya, a.z AS za, b.x AS xb, b.y AS yb, b.z AS zb, c.x AS xc, c.y AS yc, c.z AS zc
          FROM tgsis.d4dtrgl t
          JOIN tgsis.d4dvrtx a ON a.geoid = p_geoid AND a.timem = p_to_timem AND a.timet = p_to_timet AND a.nodeid = t.nodeid1
          JOIN tgsis.d4dvrtx b ON b.geoid = p_geoid AND b.timem = p_to_timem AND b.timet = p_to_timet AND b.nodeid = t.nodeid2
          JOIN tgsis.d4dvrtx c ON c.geoid = p_geoid AND c.timem = p_to_timem AND c.timet = p_to_timet AND c.nodeid = t.nodeid3
         WHERE t.geoid = p_geoid AND t.timem = p_to_timem
           AND a.x NOT IN ('NaN', 'Infinity', '-Infinity') AND a.y NOT IN ('NaN', 'Infinity', '-Infinity') AND a.z NOT IN ('NaN', 'Infinity', '-Infinity')
           AND b.x NOT IN ('NaN', 'Infinity', '-Infinity') AND b.y NOT IN ('NaN', 'Infinity', '-Infinity') AND b.z NOT IN ('NaN', 'Infinity', '-Infinity')
           AND c.x NOT IN ('NaN', 'Infinity', '-Infinity') AND c.y NOT IN ('NaN', 'Infinity', '-Infinity') AND c.z NOT IN ('NaN', 'Infinity', '-Infinity')),
    grid AS MATERIALIZED (
        SELECT tri.*, e.i0 + i AS i, e.j0 + j AS j, e.k0 + k AS k
          FROM tri,
               LATERAL (SELECT floor((least(xa, xb, xc) - p_tolerance) / v_cell) AS i0, floor((greatest(xa, xb, xc) + p_tolerance) / v_cell) AS i1,
                               floor((least(ya, yb, yc) - p_tolerance) / v_cell) AS j0, floor((greatest(ya, yb, yc) + p_tolerance) / v_cell) AS j1,
                               floor((least(za, zb, zc) - p_tolerance) / v_cell) AS k0, floor((greatest(za, zb, zc) + p_tolerance) / v_cell) AS k1) e,
               generate_series(0, (e.i1 - e.i0)::int) i, generate_series(0, (e.j1 - e.j0)::int) j,
               generate_series(0, (e.k1 - e.k0)::int) k),
    near AS (
        SELECT p.nodeid, min(tgsis.point_triangle_distance(p.x, p.y, p.z, g.xa, g.ya, g.za, g.xb, g.yb, g.zb, g.xc, g.yc, g.zc)) AS d
          FROM tgsis.d4dvrtx p
          LEFT JOIN grid g ON g.i = floor(p.x / v_cell) AND g.j = floor(p.y / v_cell) AND g.k = floor(p.z / v_cell)
               -- and the node in the triangle's box grown by the tolerance: a triangle outside it is farther than
               -- the tolerance, so the exact distance (a PL/pgSQL call) is computed for the few that hold the node
               AND p.x BETWEEN least(g.xa, g.xb, g.xc) - p_tolerance AND greatest(g.xa, g.xb, g.xc) + p_tolerance
               AND p.y BETWEEN least(g.ya, g.yb, g.yc) - p_tolerance AND greatest(g.ya, g.yb, g.yc) + p_tolerance
               AND p.z BETWEEN least(g.za, g.zb, g.zc) - p_tolerance AND greatest(g.za, g.zb, g.zc) + p_tolerance
         WHERE p.geoid = p_geoid AND p.timem = p_from_timem AND p.timet = p_from_timet
           AND p.x NOT IN ('NaN', 'Infinity', '-Infinity') AND p.y NOT IN ('NaN', 'Infinity', '-Infinity') AND p.z NOT IN ('NaN', 'Infinity', '-Infinity')
         GROUP BY p.nodeid)
    SELECT max(n.d) FILTER (WHERE n.d <= p_tolerance),
           (array_agg(n.nodeid ORDER BY n.d DESC) FILTER (WHERE n.d <= p_tolerance))[1],
           array_agg(n.nodeid ORDER BY n.nodeid) FILTER (WHERE n.d IS NULL OR n.d > p_tolerance)
      INTO v_gap, v_node, v_far
      FROM near n;

    exact := true;
    IF v_far IS NOT NULL THEN
        -- nodes farther than the tolerance from every candidate: measured against all the triangles
        v_limit := greatest(1, 2000000 / v_ntri);
        IF cardinality(v_far) > v_limit THEN
            v_far := v_far[1:v_limit];
            exact := false;
        END IF;
        SELECT f.d, f.nodeid INTO v_gap2, v_node2
          FROM (SELECT p.nodeid,
                       min(tgsis.point_triangle_distance(p.x, p.y, p.z, a.x, a.y, a.z, b.x, b.y, b.z, c.x, c.y, c.z)) AS d
                  FROM tgsis.d4dvrtx p
                  CROSS JOIN tgsis.d4dtrgl t
                  JOIN tgsis.d4dvrtx a ON a.geoid = p_geoid AND a.timem = p_to_timem AND a.timet = p_to_timet AND a.nodeid = t.nodeid1
                  JOIN tgsis.d4dvrtx b ON b.geoid = p_geoid AND b.timem = p_to_timem AND b.timet = p_to_timet AND b.nodeid = t.nodeid2
                  JOIN tgsis.d4dvrtx c ON c.geoid = p_geoid AND c.timem = p_to_timem AND c.timet = p_to_timet AND c.nodeid = t.nodeid3
                 WHERE p.geoid = p_geoid AND p.timem = p_from_timem AND p.timet = p_from_timet AND p.nodeid = ANY (v_far)
                   AND t.geoid = p_geoid AND t.timem = p_to_timem
                   AND a.x NOT IN ('NaN', 'Infinity', '-Infinity') AND a.y NOT IN ('NaN', 'Infinity', '-Infinity') AND a.z NOT IN ('NaN', 'Infinity', '-Infinity')
                   AND b.x NOT IN ('NaN', 'Infinity', '-Infinity') AND b.y NOT IN ('NaN', 'Infinity', '-Infinity') AND b.z NOT IN ('NaN', 'Infinity', '-Infinity')
                   AND c.x NOT IN ('NaN', 'Infinity', '-Infinity') AND c.y NOT IN ('NaN', 'Infinity', '-Infinity') AND c.z NOT IN ('NaN', 'Infinity', '-Infinity')
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

COMMENT ON FUNCTION tgsis.surface_side_gap(bigint, double precision, double precision, double precision, double precision,
                                           double precision) IS
    'model 3: the largest distance from a node of the shape at (from period, instant) to the triangles of the shape at (to period, instant), its node, and whether it is exact (false: at least that, measured on the first 2,000,000 node-triangle pairs of the far nodes); one side of tgsis.period_gaps';
