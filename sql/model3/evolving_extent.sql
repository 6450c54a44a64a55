-- tgsis.evolving_extent(geoid): bounding box and counts of an evolving surface (model 3) over all its periods.
-- Model 3's extent function in the registry (tgsis.data_models), read by
-- tgsis.refresh_geometry: the box holds every node position at every geometry
-- instant, which holds every shape in between (nodes move on straight lines).
CREATE FUNCTION tgsis.evolving_extent(p_geoid bigint)
RETURNS TABLE (bbox cube, nvrtx bigint, ncell bigint)
LANGUAGE plpgsql
STABLE
SET search_path FROM CURRENT
AS $$
BEGIN
    SELECT count(*) INTO ncell FROM tgsis.d4dtrgl c WHERE c.geoid = p_geoid;
    SELECT count(*) INTO nvrtx FROM tgsis.node n WHERE n.geoid = p_geoid;
    SELECT CASE WHEN count(*) > 0 THEN cube(ARRAY[min(v.x), min(v.y), min(v.z)], ARRAY[max(v.x), max(v.y), max(v.z)]) END
      INTO bbox
      FROM tgsis.d4dvrtx v WHERE v.geoid = p_geoid;
    RETURN NEXT;
END
$$;

COMMENT ON FUNCTION tgsis.evolving_extent(bigint) IS
    'bbox of every node position at every geometry instant, number of nodes and of triangles of an evolving surface (model 3) over all its periods; model 3''s extent function (tgsis.data_models)';
