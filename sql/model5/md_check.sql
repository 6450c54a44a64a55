-- tgsis.md_check(geoid): the conditions of a stored multiply indexed G-map (model 5), with the offending darts (no rows: valid).
-- The conditions every G-map model shares (tgsis.gmap_conditions: (i)-(iii),
-- one point per 0-cell, rows that refer to darts) and model 5's own: darts
-- of points that exist (proved by the points' numbering, or by a join
-- naming the darts).
CREATE FUNCTION tgsis.md_check(p_geoid bigint)
RETURNS TABLE (problem text, count bigint, darts bigint[])
LANGUAGE plpgsql
STABLE
SET search_path FROM CURRENT
AS $$
DECLARE
    v_n smallint;
BEGIN
    SELECT g.dimension INTO v_n FROM tgsis.md_gmap g WHERE g.geoid = p_geoid;
    IF NOT FOUND THEN
        RAISE EXCEPTION 'geometry % is not a stored multiply indexed G-map', p_geoid
            USING ERRCODE = 'TG200', HINT = 'SELECT geoid FROM tgsis.md_gmap lists them';
    END IF;
    RETURN QUERY SELECT * FROM tgsis.gmap_conditions(p_geoid, v_n, 'tgsis.md_dart', 'tgsis.md_alpha', 'vrtxid');
    -- the darts' points exist: proved without a join when the points are
    -- numbered densely (as tgsis.insert_gmap numbers them) over a range
    -- that holds the darts' points
    IF (SELECT coalesce(count(v.vrtxid) = max(v.vrtxid) - min(v.vrtxid) + 1 AND min(v.vrtxid) <= d.lo AND max(v.vrtxid) >= d.hi, d.lo IS NULL)
          FROM (SELECT min(g.vrtxid) AS lo, max(g.vrtxid) AS hi FROM tgsis.md_dart g WHERE g.geoid = p_geoid) AS d
          LEFT JOIN tgsis.md_vertex v ON v.geoid = p_geoid
         GROUP BY d.lo, d.hi) THEN
        RETURN;
    END IF;
    RETURN QUERY
        SELECT 'dart of a point that does not exist'::text, count(*), (array_agg(d.dartid ORDER BY d.dartid))[1:20]
          FROM tgsis.md_dart d
         WHERE d.geoid = p_geoid
           AND NOT EXISTS (SELECT FROM tgsis.md_vertex v WHERE v.geoid = p_geoid AND v.vrtxid = d.vrtxid)
        HAVING count(*) > 0;
END
$$;

COMMENT ON FUNCTION tgsis.md_check(bigint) IS
    'problems of a stored multiply indexed G-map (model 5) with the first offending darts: those of tgsis.gmap_conditions and darts of missing points; no rows: valid';
