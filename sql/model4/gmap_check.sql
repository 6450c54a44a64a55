-- tgsis.gmap_check(geoid): the conditions of an n-G-map and of its periods, with the offending darts (no rows: valid).
-- The conditions every G-map model shares (tgsis.gmap_conditions: (i)-(iii),
-- one point per 0-cell, rows that refer to darts), and model 4's own: every
-- involution keeps a dart in its topology period (the closure of the
-- partition D0..Dk), darts of nodes and periods that exist. darts lists the
-- first offending darts (at most 20), count all of them.
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
    RETURN QUERY SELECT * FROM tgsis.gmap_conditions(p_geoid, v_n, 'tgsis.gmap_dart', 'tgsis.gmap_alpha', 'nodeid');
    -- the partition into periods, the shared nodes of 0-cells, nodes of the dart's period
    RETURN QUERY
        SELECT format('alpha_%s sends a dart into another topology period', a.level), count(*),
               (array_agg(a.dartid ORDER BY a.dartid))[1:20]
          FROM tgsis.gmap_alpha a
          JOIN tgsis.gmap_dart d ON d.geoid = a.geoid AND d.dartid = a.dartid
          JOIN tgsis.gmap_dart e ON e.geoid = a.geoid AND e.dartid = a.dartid2
         WHERE a.geoid = p_geoid AND d.timem <> e.timem
         GROUP BY a.level ORDER BY a.level;
    RETURN QUERY
        SELECT 'dart of a node missing from its topology period'::text, count(*), (array_agg(d.dartid ORDER BY d.dartid))[1:20]
          FROM tgsis.gmap_dart d
         WHERE d.geoid = p_geoid
           AND NOT EXISTS (SELECT FROM tgsis.gmap_node n WHERE n.geoid = p_geoid AND n.timem = d.timem AND n.nodeid = d.nodeid)
        HAVING count(*) > 0;
    RETURN QUERY
        SELECT 'dart of a topology period that does not exist'::text, count(*), (array_agg(d.dartid ORDER BY d.dartid))[1:20]
          FROM tgsis.gmap_dart d
         WHERE d.geoid = p_geoid
           AND NOT EXISTS (SELECT FROM tgsis.gmap_timem m WHERE m.geoid = p_geoid AND m.timem = d.timem)
        HAVING count(*) > 0;
END
$$;

COMMENT ON FUNCTION tgsis.gmap_check(bigint) IS
    'problems of a stored G-map (model 4) with the first offending darts: missing or dangling alpha rows, (i) non-involutions, (ii) fixed points below alpha_n, (iii) alpha_i o alpha_j not involutions (i + 2 <= j), darts sent into another topology period, 0-cells with several nodes, darts of missing nodes or periods; no rows: valid';
