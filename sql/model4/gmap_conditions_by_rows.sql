-- tgsis.gmap_conditions_by_rows(geoid, n, darts, alpha, point, period): tgsis.gmap_conditions by keyed joins, for rows of any shape.
-- What tgsis.gmap_conditions runs when the rows cannot be read as arrays
-- (tgsis.gmap_alpha_array is NULL: missing, extra or dangling rows, holes
-- in the dart numbering), and what its array path is tested against.
-- Set-based: one keyed join per condition and level. (i) every alpha_i is an involution; (ii) no dart is free in
-- alpha_i for i < n; (iii) alpha_i o alpha_j is an involution for
-- i + 2 <= j; the darts of one 0-cell share their point (alpha_1 .. alpha_n
-- keep it); the rows refer to what exists (a row per dart and level, images
-- that are darts); with a period column (model 4), every alpha_i keeps a
-- dart in its period. darts lists the first offending darts (at most 20).
-- The tables are given as regclass (quoted by their output), the columns
-- by name (%I): no caller text reaches the SQL unquoted.
CREATE FUNCTION tgsis.gmap_conditions_by_rows(p_geoid bigint, p_n integer, p_dart regclass, p_alpha regclass, p_point text,
                                              p_period text DEFAULT NULL)
RETURNS TABLE (problem text, count bigint, darts bigint[])
LANGUAGE plpgsql
STABLE
SET search_path FROM CURRENT
AS $$
DECLARE
    v_i integer;
    v_j integer;
BEGIN
    RETURN QUERY EXECUTE format(
        'SELECT format(''dart has no alpha_%%s row'', l.level), count(*), (array_agg(d.dartid ORDER BY d.dartid))[1:20]
           FROM %1$s d CROSS JOIN generate_series(0, $2) AS l (level)
          WHERE d.geoid = $1
            AND NOT EXISTS (SELECT FROM %2$s a WHERE a.geoid = $1 AND a.level = l.level AND a.dartid = d.dartid)
          GROUP BY l.level ORDER BY l.level', p_dart, p_alpha) USING p_geoid, p_n;
    RETURN QUERY EXECUTE format(
        'SELECT CASE WHEN a.level > $2 THEN format(''alpha_%%s row above the dimension %%s'', a.level, $2)
                     ELSE format(''alpha_%%s row of a missing dart or to a missing dart'', a.level) END,
                count(*), (array_agg(a.dartid ORDER BY a.dartid))[1:20]
           FROM %2$s a
          WHERE a.geoid = $1
            AND (a.level > $2
                 OR NOT EXISTS (SELECT FROM %1$s d WHERE d.geoid = $1 AND d.dartid = a.dartid)
                 OR NOT EXISTS (SELECT FROM %1$s d WHERE d.geoid = $1 AND d.dartid = a.dartid2))
          GROUP BY a.level > $2, a.level ORDER BY a.level', p_dart, p_alpha) USING p_geoid, p_n;
    -- (i) and (ii)
    RETURN QUERY EXECUTE format(
        'SELECT format(''alpha_%%s is not an involution'', a.level), count(*), (array_agg(a.dartid ORDER BY a.dartid))[1:20]
           FROM %1$s a
           LEFT JOIN %1$s b ON b.geoid = a.geoid AND b.level = a.level AND b.dartid = a.dartid2
          WHERE a.geoid = $1 AND a.level <= $2 AND b.dartid2 IS DISTINCT FROM a.dartid
          GROUP BY a.level ORDER BY a.level', p_alpha) USING p_geoid, p_n;
    RETURN QUERY EXECUTE format(
        'SELECT format(''dart free in alpha_%%s (only alpha_%%s may have fixed points)'', a.level, $2), count(*),
                (array_agg(a.dartid ORDER BY a.dartid))[1:20]
           FROM %1$s a
          WHERE a.geoid = $1 AND a.level < $2 AND a.dartid2 = a.dartid
          GROUP BY a.level ORDER BY a.level', p_alpha) USING p_geoid, p_n;
    -- (iii): alpha_i(alpha_j(alpha_i(alpha_j(d)))) = d
    FOR v_i IN 0 .. p_n - 2 LOOP
        FOR v_j IN v_i + 2 .. p_n LOOP
            RETURN QUERY EXECUTE format(
                'SELECT format(''alpha_%%s o alpha_%%s is not an involution'', $2, $3), count(*),
                        (array_agg(j1.dartid ORDER BY j1.dartid))[1:20]
                   FROM %1$s j1
                   LEFT JOIN %1$s i1 ON i1.geoid = $1 AND i1.level = $2 AND i1.dartid = j1.dartid2
                   LEFT JOIN %1$s j2 ON j2.geoid = $1 AND j2.level = $3 AND j2.dartid = i1.dartid2
                   LEFT JOIN %1$s i2 ON i2.geoid = $1 AND i2.level = $2 AND i2.dartid = j2.dartid2
                  WHERE j1.geoid = $1 AND j1.level = $3 AND i2.dartid2 IS DISTINCT FROM j1.dartid
                 HAVING count(*) > 0', p_alpha) USING p_geoid, v_i, v_j;
        END LOOP;
    END LOOP;
    -- the darts of one 0-cell share their point
    RETURN QUERY EXECUTE format(
        'SELECT format(''alpha_%%s joins darts of different points (a 0-cell has one point)'', a.level), count(*),
                (array_agg(a.dartid ORDER BY a.dartid))[1:20]
           FROM %2$s a
           JOIN %1$s d ON d.geoid = a.geoid AND d.dartid = a.dartid
           JOIN %1$s e ON e.geoid = a.geoid AND e.dartid = a.dartid2
          WHERE a.geoid = $1 AND a.level >= 1 AND d.%3$I <> e.%3$I
          GROUP BY a.level ORDER BY a.level', p_dart, p_alpha, p_point) USING p_geoid;
    -- the closure of the partition into periods
    IF p_period IS NOT NULL THEN
        RETURN QUERY EXECUTE format(
            'SELECT format(''alpha_%%s sends a dart into another topology period'', a.level), count(*),
                    (array_agg(a.dartid ORDER BY a.dartid))[1:20]
               FROM %2$s a
               JOIN %1$s d ON d.geoid = a.geoid AND d.dartid = a.dartid
               JOIN %1$s e ON e.geoid = a.geoid AND e.dartid = a.dartid2
              WHERE a.geoid = $1 AND d.%3$I <> e.%3$I
              GROUP BY a.level ORDER BY a.level', p_dart, p_alpha, p_period) USING p_geoid;
    END IF;
END
$$;

COMMENT ON FUNCTION tgsis.gmap_conditions_by_rows(bigint, integer, regclass, regclass, text, text) IS
    'tgsis.gmap_conditions by keyed joins over rows of any shape (what it runs when tgsis.gmap_alpha_array is NULL)';
