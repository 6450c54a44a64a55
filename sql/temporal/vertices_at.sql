-- tgsis.vertices_at(geoid, t, convention): the vertices of a surface at model time t (ids as stored; any order).
-- Model 3: nodes of the period containing t, each moved linearly between the
-- bracketing geometry instants, x(t) = x0 + w (x1 - x0); at a geometry
-- instant exactly, the stored positions (one index scan, no join). Model 2:
-- the vertices of the instant tgsis.instant_at chooses. Static geometries:
-- their vertices at every t. One set-based query, inlined into the caller.
--
-- The frame is read through scalar subqueries (InitPlans), not joined: their
-- values are constants to the planner, so each side of the join is an index
-- scan of (geoid, timem, timet) that returns one instant's nodes in nodeid
-- order, and the two sides merge-join (or hash-join) on nodeid. Joined to the
-- frame instead, the planner could not bound d4dvrtx by the instants: it
-- scanned every row of the table (all instants, all surfaces) into a hash
-- join (see docs/performance.md). Model 2's instant too (a scalar subquery):
-- compared as `times = tgsis.instant_at(f.geoid, ...)` under a LATERAL call it
-- was a filter over the versioned view, run per row of every instant
-- (tests/test_instant_at_once.py).
--
-- Model 3 between two geometry instants with tgsis.d4dvrtx stored in chunks
-- (the view tgsis.d4dvrtx_arrays exists, made by the switch) and the caller
-- allowed to read those arrays and the face (the arrays hold rows only for a
-- caller who may read the face: a GRANT or REVOKE on it reaches them): tgsis.evolving_chunk_vertices interpolates the
-- two instants' aligned chunk arrays slot by slot (the same operations, the
-- same bits) instead of decoding both instants through the face and joining
-- them; a caller who may read the face but not the arrays, and rows storage,
-- take the join below (one of the two branches runs, decided once per query by
-- c). At a geometry instant the face's one scan on either storage: as fast as
-- the arrays there, without the PL/pgSQL function's result set
-- (docs/performance.md, "Model 3's SQL snapshot on the arrays").
CREATE FUNCTION tgsis.vertices_at(p_geoid bigint, p_t double precision, p_convention text DEFAULT 'left')
RETURNS TABLE (vrtxid bigint, x double precision, y double precision, z double precision)
LANGUAGE sql
STABLE
PARALLEL SAFE
AS $$
    WITH f AS MATERIALIZED (SELECT * FROM tgsis.evolving_frame(p_geoid, p_t)),
    c AS MATERIALIZED (  -- d4dvrtx in chunks and its arrays readable by the caller: model 3 from the arrays
        SELECT coalesce(has_table_privilege(to_regclass('tgsis.d4dvrtx_arrays'), 'SELECT')
                        AND has_table_privilege(to_regclass('tgsis.d4dvrtx'), 'SELECT'), false) AS arrays
    )
    SELECT s.vrtxid, s.x, s.y, s.z
      FROM tgsis.evolving_chunk_vertices(p_geoid, (SELECT f.timem FROM f), (SELECT f.t0 FROM f), (SELECT f.t1 FROM f),
                                         (SELECT f.w FROM f)) s
     WHERE (SELECT c.arrays FROM c) AND (SELECT f.t0 < f.t1 FROM f)
       AND tgsis.checked_convention(p_convention) IS NOT NULL
    UNION ALL
    SELECT a.nodeid, a.x + (SELECT f.w FROM f) * (b.x - a.x), a.y + (SELECT f.w FROM f) * (b.y - a.y),
           a.z + (SELECT f.w FROM f) * (b.z - a.z)
      FROM tgsis.d4dvrtx a
      JOIN tgsis.d4dvrtx b ON b.nodeid = a.nodeid
     WHERE a.geoid = p_geoid AND a.timem = (SELECT f.timem FROM f) AND a.timet = (SELECT f.t0 FROM f)
       AND b.geoid = p_geoid AND b.timem = (SELECT f.timem FROM f) AND b.timet = (SELECT f.t1 FROM f)
       AND (SELECT f.t0 < f.t1 FROM f) AND (SELECT NOT c.arrays FROM c)
       AND tgsis.checked_convention(p_convention) IS NOT NULL  -- model 3 has no steps, but a bad value is an error
    UNION ALL
    SELECT a.nodeid, a.x, a.y, a.z
      FROM tgsis.d4dvrtx a
     WHERE a.geoid = p_geoid AND a.timem = (SELECT f.timem FROM f) AND a.timet = (SELECT f.t0 FROM f)
       AND (SELECT f.t0 = f.t1 FROM f)
       AND tgsis.checked_convention(p_convention) IS NOT NULL
    UNION ALL
    SELECT v.vrtxid, v.x, v.y, v.z
      FROM tgsis.times_vrtx v
     WHERE v.geoid = p_geoid AND v.times = (SELECT tgsis.instant_at(p_geoid, p_t, p_convention))
    UNION ALL
    SELECT v.vrtxid, v.x, v.y, v.z
      FROM tgsis.vrtx v
     WHERE v.geoid = p_geoid
       AND EXISTS (SELECT FROM tgsis.geometry g WHERE g.geoid = p_geoid AND g.timemodel = 'STATIC')
       AND tgsis.checked_convention(p_convention) IS NOT NULL
    UNION ALL   -- another model is refused (TG203), not answered empty
    SELECT NULL, NULL, NULL, NULL
      FROM tgsis.geometry g
     WHERE g.geoid = p_geoid AND g.timemodel NOT IN ('STATIC', 'INSTANTS', 'EVOLVING')
       AND tgsis.no_model_rule(g.timemodel, 'tgsis.vertices_at', '{STATIC,INSTANTS,EVOLVING}')
$$;

COMMENT ON FUNCTION tgsis.vertices_at(bigint, double precision, text) IS
    'vertices (vrtxid, x, y, z) of a geometry at model time t: model 3 interpolated linearly in the period containing t, model 2 by the left- or right-closed step convention, static ones always; empty when the object does not exist at t';
