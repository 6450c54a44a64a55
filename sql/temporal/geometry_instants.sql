-- tgsis.geometry_instants(geoid): the instants of a temporal geometry, ascending, and whether its topology is (re)defined there.
-- Model 2: every instant (each has its own triangles). Model 3: every
-- geometry instant; topology is true at the start of each period.
CREATE FUNCTION tgsis.geometry_instants(p_geoid bigint)
RETURNS TABLE (t double precision, topology boolean)
LANGUAGE sql
STABLE
PARALLEL SAFE
AS $$
    SELECT i.times, true FROM tgsis.times i WHERE i.geoid = p_geoid
    UNION ALL
    SELECT i.timet, bool_or(i.timet = i.timem) FROM tgsis.timet i WHERE i.geoid = p_geoid GROUP BY i.timet
    ORDER BY 1
$$;

COMMENT ON FUNCTION tgsis.geometry_instants(bigint) IS
    'instants of a temporal geometry in ascending order, with topology = true where its topology is (re)defined (every instant of model 2, period starts of model 3); empty for static geometries';
