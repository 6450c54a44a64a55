-- tgsis.gmap_frame(geoid, t): where t falls in a G-map (model 4): its topology period, the bracketing geometry instants t0 <= t <= t1 and the weight w = (t - t0) / (t1 - t0).
-- The rules of model 3 (tgsis.evolving_frame, tgsis.temporal.frame_at): the
-- period is the last topology instant <= t; no row before the first instant,
-- nor after the last geometry instant unless the geometry is alive (then
-- t0 = t1 = the last, w = 0).
CREATE FUNCTION tgsis.gmap_frame(p_geoid bigint, p_t double precision)
RETURNS TABLE (timem double precision, t0 double precision, t1 double precision, w double precision)
LANGUAGE plpgsql
STABLE
SET search_path FROM CURRENT
AS $$
BEGIN
    -- (PL/pgSQL: the model-4 tables do not exist yet when the extension script runs)
    RETURN QUERY
    WITH period AS (
        SELECT m.timem,
               NOT EXISTS (SELECT FROM tgsis.gmap_timem n WHERE n.geoid = p_geoid AND n.timem > m.timem) AS last
          FROM tgsis.gmap_timem m
         WHERE m.geoid = p_geoid AND m.timem <= tgsis.checked_time(p_t)
         ORDER BY m.timem DESC
         LIMIT 1
    ), bracket AS (
        SELECT p.timem, p.last,
               (SELECT max(i.timet) FROM tgsis.gmap_timet i WHERE i.geoid = p_geoid AND i.timem = p.timem AND i.timet <= p_t) AS lo,
               (SELECT min(i.timet) FROM tgsis.gmap_timet i WHERE i.geoid = p_geoid AND i.timem = p.timem AND i.timet >= p_t) AS hi
          FROM period p
    )
    SELECT b.timem, b.lo, coalesce(b.hi, b.lo),
           CASE WHEN b.hi IS NULL OR b.hi = b.lo THEN 0::double precision ELSE (p_t - b.lo) / (b.hi - b.lo) END
      FROM bracket b
      JOIN tgsis.geometry g ON g.geoid = p_geoid
     WHERE b.lo IS NOT NULL
       AND (b.hi IS NOT NULL OR g.alive OR NOT b.last);
END
$$;

COMMENT ON FUNCTION tgsis.gmap_frame(bigint, double precision) IS
    'model 4: topology period (timem) and bracketing geometry instants t0 <= t <= t1 of a G-map at t, with w = (t - t0)/(t1 - t0); no row when it does not exist at t';
