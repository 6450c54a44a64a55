-- tgsis.vertices_at(geoid, t, convention): the vertices of a surface at model time t (ids as stored; any order).
-- Model 3: nodes of the period containing t, each moved linearly between the
-- bracketing geometry instants, x(t) = x0 + w (x1 - x0). Model 2: the
-- vertices of the instant tgsis.instant_at chooses. Static geometries: their
-- vertices at every t. One set-based query.
CREATE FUNCTION tgsis.vertices_at(p_geoid bigint, p_t double precision, p_convention text DEFAULT 'left')
RETURNS TABLE (vrtxid bigint, x double precision, y double precision, z double precision)
LANGUAGE sql
STABLE
PARALLEL SAFE
AS $$
    SELECT a.nodeid, a.x + f.w * (b.x - a.x), a.y + f.w * (b.y - a.y), a.z + f.w * (b.z - a.z)
      FROM tgsis.evolving_frame(p_geoid, p_t) f
      JOIN tgsis.d4dvrtx a ON a.geoid = p_geoid AND a.timem = f.timem AND a.timet = f.t0
      JOIN tgsis.d4dvrtx b ON b.geoid = p_geoid AND b.timem = f.timem AND b.timet = f.t1 AND b.nodeid = a.nodeid
     WHERE tgsis.checked_convention(p_convention) IS NOT NULL  -- model 3 has no steps, but a bad value is an error
    UNION ALL
    SELECT v.vrtxid, v.x, v.y, v.z
      FROM tgsis.times_vrtx v
     WHERE v.geoid = p_geoid AND v.times = tgsis.instant_at(p_geoid, p_t, p_convention)
    UNION ALL
    SELECT v.vrtxid, v.x, v.y, v.z
      FROM tgsis.vrtx v
     WHERE v.geoid = p_geoid
       AND EXISTS (SELECT FROM tgsis.geometry g WHERE g.geoid = p_geoid AND g.timemodel = 'STATIC')
       AND tgsis.checked_convention(p_convention) IS NOT NULL
$$;

COMMENT ON FUNCTION tgsis.vertices_at(bigint, double precision, text) IS
    'vertices (vrtxid, x, y, z) of a geometry at model time t: model 3 interpolated linearly in the period containing t, model 2 by the left- or right-closed step convention, static ones always; empty when the object does not exist at t';
