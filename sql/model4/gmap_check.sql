-- tgsis.gmap_check(geoid): the conditions of an n-G-map and of its periods, with the offending darts (no rows: valid).
-- Set-based over the stored rows, one keyed join per condition and level:
-- (i) every alpha_i is an involution; (ii) no dart is free in alpha_i for
-- i < n; (iii) alpha_i o alpha_j is an involution for i + 2 <= j; every
-- involution keeps a dart in its topology period (the closure of the
-- partition D0..Dk); the darts of one 0-cell share their node (alpha_1 ..
-- alpha_n keep the node); and the rows refer to what exists (a row per dart
-- and level, images that are darts, nodes of the dart's period). darts
-- lists the first offending darts (at most 20), count all of them.
CREATE FUNCTION tgsis.gmap_check(p_geoid bigint)
RETURNS TABLE (problem text, count bigint, darts bigint[])
LANGUAGE plpgsql
STABLE
SET search_path FROM CURRENT
AS $$
DECLARE
    v_n smallint;
    v_i smallint;
    v_j smallint;
BEGIN
    SELECT g.dimension INTO v_n FROM tgsis.gmap g WHERE g.geoid = p_geoid;
    IF NOT FOUND THEN
        RAISE EXCEPTION 'geometry % is not a stored G-map', p_geoid
            USING ERRCODE = 'TG200', HINT = 'SELECT geoid FROM tgsis.gmap lists the stored G-maps';
    END IF;
    RETURN QUERY
        SELECT format('dart has no alpha_%s row', l.level), count(*), (array_agg(d.dartid ORDER BY d.dartid))[1:20]
          FROM tgsis.gmap_dart d CROSS JOIN generate_series(0, v_n) AS l (level)
         WHERE d.geoid = p_geoid
           AND NOT EXISTS (SELECT FROM tgsis.gmap_alpha a WHERE a.geoid = p_geoid AND a.level = l.level AND a.dartid = d.dartid)
         GROUP BY l.level ORDER BY l.level;
    RETURN QUERY
        SELECT CASE WHEN a.level > v_n THEN format('alpha_%s row above the dimension %s', a.level, v_n)
                    ELSE format('alpha_%s row of a missing dart or to a missing dart', a.level) END,
               count(*), (array_agg(a.dartid ORDER BY a.dartid))[1:20]
          FROM tgsis.gmap_alpha a
         WHERE a.geoid = p_geoid
           AND (a.level > v_n
                OR NOT EXISTS (SELECT FROM tgsis.gmap_dart d WHERE d.geoid = p_geoid AND d.dartid = a.dartid)
                OR NOT EXISTS (SELECT FROM tgsis.gmap_dart d WHERE d.geoid = p_geoid AND d.dartid = a.dartid2))
         GROUP BY a.level > v_n, a.level ORDER BY a.level;
    -- (i) and (ii)
    RETURN QUERY
        SELECT format('alpha_%s is not an involution', a.level), count(*), (array_agg(a.dartid ORDER BY a.dartid))[1:20]
          FROM tgsis.gmap_alpha a
          LEFT JOIN tgsis.gmap_alpha b ON b.geoid = a.geoid AND b.level = a.level AND b.dartid = a.dartid2
         WHERE a.geoid = p_geoid AND a.level <= v_n AND b.dartid2 IS DISTINCT FROM a.dartid
         GROUP BY a.level ORDER BY a.level;
    RETURN QUERY
        SELECT format('dart free in alpha_%s (only alpha_%s may have fixed points)', a.level, v_n), count(*),
               (array_agg(a.dartid ORDER BY a.dartid))[1:20]
          FROM tgsis.gmap_alpha a
         WHERE a.geoid = p_geoid AND a.level < v_n AND a.dartid2 = a.dartid
         GROUP BY a.level ORDER BY a.level;
    -- (iii): alpha_i(alpha_j(alpha_i(alpha_j(d)))) = d
    FOR v_i IN 0 .. v_n - 2 LOOP
        FOR v_j IN v_i + 2 .. v_n LOOP
            RETURN QUERY
                SELECT format('alpha_%s o alpha_%s is not an involution', v_i, v_j), count(*),
                       (array_agg(j1.dartid ORDER BY j1.dartid))[1:20]
                  FROM tgsis.gmap_alpha j1
                  LEFT JOIN tgsis.gmap_alpha i1 ON i1.geoid = p_geoid AND i1.level = v_i AND i1.dartid = j1.dartid2
                  LEFT JOIN tgsis.gmap_alpha j2 ON j2.geoid = p_geoid AND j2.level = v_j AND j2.dartid = i1.dartid2
                  LEFT JOIN tgsis.gmap_alpha i2 ON i2.geoid = p_geoid AND i2.level = v_i AND i2.dartid = j2.dartid2
                 WHERE j1.geoid = p_geoid AND j1.level = v_j AND i2.dartid2 IS DISTINCT FROM j1.dartid
                HAVING count(*) > 0;
        END LOOP;
    END LOOP;
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
        SELECT format('alpha_%s joins darts of different nodes (a 0-cell has one point)', a.level), count(*),
               (array_agg(a.dartid ORDER BY a.dartid))[1:20]
          FROM tgsis.gmap_alpha a
          JOIN tgsis.gmap_dart d ON d.geoid = a.geoid AND d.dartid = a.dartid
          JOIN tgsis.gmap_dart e ON e.geoid = a.geoid AND e.dartid = a.dartid2
         WHERE a.geoid = p_geoid AND a.level >= 1 AND d.nodeid <> e.nodeid
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
