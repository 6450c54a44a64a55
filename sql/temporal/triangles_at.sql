-- tgsis.triangles_at(geoid, t, convention): the triangles of a surface at model time t, pointing at the vrtxid of tgsis.vertices_at.
-- The period comes from a scalar subquery (a constant to the planner, as in
-- tgsis.vertices_at): an index scan of that period, not a scan of every period.
-- So does model 2's instant: `times = tgsis.instant_at(...)` of a column
-- (LATERAL over several geoids, as the Python readers call it) was a filter
-- over the versioned view, run per row of every instant (tests/test_instant_at_once.py).
CREATE FUNCTION tgsis.triangles_at(p_geoid bigint, p_t double precision, p_convention text DEFAULT 'left')
RETURNS TABLE (trglid bigint, vrtxid1 bigint, vrtxid2 bigint, vrtxid3 bigint)
LANGUAGE sql
STABLE
PARALLEL SAFE
AS $$
    SELECT c.trglid, c.nodeid1, c.nodeid2, c.nodeid3
      FROM tgsis.d4dtrgl c
     WHERE c.geoid = p_geoid AND c.timem = (SELECT f.timem FROM tgsis.evolving_frame(p_geoid, p_t) f)
       AND tgsis.checked_convention(p_convention) IS NOT NULL  -- model 3 has no steps, but a bad value is an error
    UNION ALL
    SELECT c.trglid, c.vrtxid1, c.vrtxid2, c.vrtxid3
      FROM tgsis.times_trgl c
     WHERE c.geoid = p_geoid AND c.times = (SELECT tgsis.instant_at(p_geoid, p_t, p_convention))
    UNION ALL
    SELECT c.trglid, c.vrtxid1, c.vrtxid2, c.vrtxid3
      FROM tgsis.trgl c
     WHERE c.geoid = p_geoid
       AND EXISTS (SELECT FROM tgsis.geometry g WHERE g.geoid = p_geoid AND g.timemodel = 'STATIC')
       AND tgsis.checked_convention(p_convention) IS NOT NULL
    UNION ALL   -- another model is refused (TG203), not answered empty
    SELECT NULL, NULL, NULL, NULL
      FROM tgsis.geometry g
     WHERE g.geoid = p_geoid AND g.timemodel NOT IN ('STATIC', 'INSTANTS', 'EVOLVING')
       AND tgsis.no_model_rule(g.timemodel, 'tgsis.triangles_at', '{STATIC,INSTANTS,EVOLVING}')
$$;

COMMENT ON FUNCTION tgsis.triangles_at(bigint, double precision, text) IS
    'triangles (trglid, vrtxid1..3) of a surface at model time t, with the period (model 3) or instant (model 2) tgsis.vertices_at uses; empty when it does not exist at t';
