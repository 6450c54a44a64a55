-- tgsis.static_extent(geoid): bounding box and counts of a static (model-1) geometry from its vertex and simplex rows.
-- Model 1's extent function in the registry (tgsis.data_models), read by
-- tgsis.refresh_geometry. PL/pgSQL: the tables do not exist yet when the
-- extension script runs.
CREATE FUNCTION tgsis.static_extent(p_geoid bigint)
RETURNS TABLE (bbox cube, nvrtx bigint, ncell bigint)
LANGUAGE plpgsql
STABLE
SET search_path FROM CURRENT
AS $$
DECLARE
    v_table text;
BEGIN
    SELECT tgsis.simplex_table(g.geotype) INTO v_table FROM tgsis.geometry g WHERE g.geoid = p_geoid;
    EXECUTE format('SELECT count(*) FROM tgsis.%I WHERE geoid = $1', v_table) INTO ncell USING p_geoid;
    SELECT count(*),
           CASE WHEN count(*) > 0 THEN cube(ARRAY[min(v.x), min(v.y), min(v.z)], ARRAY[max(v.x), max(v.y), max(v.z)]) END
      INTO nvrtx, bbox
      FROM tgsis.vrtx v WHERE v.geoid = p_geoid;
    RETURN NEXT;
END
$$;

COMMENT ON FUNCTION tgsis.static_extent(bigint) IS
    'bbox (cube of the vertices, NULL without any), number of vertices and of simplices of a static geometry from tgsis.vrtx and its simplex table; model 1''s extent function (tgsis.data_models)';
