-- tgsis.gmap_check(geoid): the conditions of an n-G-map and of its periods, with the offending darts (no rows: valid).
-- The conditions every G-map model shares (tgsis.gmap_conditions: (i)-(iii),
-- one point per 0-cell, rows that refer to darts), and model 4's own: every
-- involution keeps a dart in its topology period (the closure of the
-- partition D0..Dk, checked by tgsis.gmap_conditions), darts of nodes and
-- periods that exist. darts lists the first offending darts (at most 20),
-- count all of them.
CREATE FUNCTION tgsis.gmap_check(p_geoid bigint)
RETURNS TABLE (problem text, count bigint, darts bigint[])
LANGUAGE plpgsql
STABLE
SET search_path FROM CURRENT
AS $$
DECLARE
    v_n smallint;
BEGIN
    SELECT g.dimension INTO v_n FROM tgsis.gmap g WHERE g.geoid = p_geoid;
    IF NOT FOUND THEN
        RAISE EXCEPTION 'geometry % is not a stored G-map', p_geoid
            USING ERRCODE = 'TG200', HINT = 'SELECT geoid FROM tgsis.gmap lists the stored G-maps';
    END IF;
    RETURN QUERY SELECT * FROM tgsis.gmap_conditions(p_geoid, v_n, 'tgsis.gmap_dart', 'tgsis.gmap_alpha', 'nodeid', 'timem');
    -- the darts' nodes and periods exist: one scan of the darts for both
    RETURN QUERY
        SELECT v.problem, v.count, v.darts
          FROM (SELECT count(*) FILTER (WHERE n.nodeid IS NULL) AS nodes,
                       (array_agg(d.dartid ORDER BY d.dartid) FILTER (WHERE n.nodeid IS NULL))[1:20] AS node_darts,
                       count(*) FILTER (WHERE m.timem IS NULL) AS periods,
                       (array_agg(d.dartid ORDER BY d.dartid) FILTER (WHERE m.timem IS NULL))[1:20] AS period_darts
                  FROM tgsis.gmap_dart d
                  LEFT JOIN tgsis.gmap_node n ON n.geoid = d.geoid AND n.timem = d.timem AND n.nodeid = d.nodeid
                  LEFT JOIN tgsis.gmap_timem m ON m.geoid = d.geoid AND m.timem = d.timem
                 WHERE d.geoid = p_geoid) AS s
         CROSS JOIN LATERAL (VALUES (1, 'dart of a node missing from its topology period', s.nodes, s.node_darts),
                                    (2, 'dart of a topology period that does not exist', s.periods, s.period_darts))
                    AS v (i, problem, count, darts)
         WHERE v.count > 0
         ORDER BY v.i;
END
$$;

COMMENT ON FUNCTION tgsis.gmap_check(bigint) IS
    'problems of a stored G-map (model 4) with the first offending darts: missing or dangling alpha rows, (i) non-involutions, (ii) fixed points below alpha_n, (iii) alpha_i o alpha_j not involutions (i + 2 <= j), darts sent into another topology period, 0-cells with several nodes, darts of missing nodes or periods; no rows: valid';
