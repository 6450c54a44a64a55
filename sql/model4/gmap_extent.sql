-- tgsis.gmap_extent(geoid): bounding box and counts of a G-map (model 4) over all its periods.
-- Model 4's extent function in the registry (tgsis.data_models), read by
-- tgsis.refresh_geometry. The box is of the first three coordinates (x, y, z;
-- 0 where the embedding has fewer), which holds every shape in between
-- (points move on straight lines); nvrtx counts nodes, ncell darts.
CREATE FUNCTION tgsis.gmap_extent(p_geoid bigint)
RETURNS TABLE (bbox cube, nvrtx bigint, ncell bigint)
LANGUAGE plpgsql
STABLE
SET search_path FROM CURRENT
AS $$
BEGIN
    SELECT count(*) INTO ncell FROM tgsis.gmap_dart d WHERE d.geoid = p_geoid;
    SELECT count(*) INTO nvrtx FROM tgsis.gmap_node n WHERE n.geoid = p_geoid;
    SELECT CASE WHEN count(*) > 0 THEN
                cube(ARRAY[min(coalesce(v.coordinate[1], 0)), min(coalesce(v.coordinate[2], 0)), min(coalesce(v.coordinate[3], 0))],
                     ARRAY[max(coalesce(v.coordinate[1], 0)), max(coalesce(v.coordinate[2], 0)), max(coalesce(v.coordinate[3], 0))])
           END
      INTO bbox
      FROM tgsis.gmap_vertex v WHERE v.geoid = p_geoid;
    RETURN NEXT;
END
$$;

COMMENT ON FUNCTION tgsis.gmap_extent(bigint) IS
    'bbox of the first three coordinates of every point at every geometry instant, number of nodes and of darts of a G-map (model 4) over all its periods; model 4''s extent function (tgsis.data_models)';
