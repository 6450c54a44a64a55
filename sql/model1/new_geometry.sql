-- tgsis.new_geometry(geotype, name, bounds, nvrtx, ncell): insert a geometry row and return its geoid.
-- The client's write path calls it before copying vertices and simplices;
-- bounds is {xmin, ymin, zmin, xmax, ymax, zmax} (NULL: no vertex).
CREATE FUNCTION tgsis.new_geometry(
    p_geotype text,
    p_name    text,
    p_bounds  double precision[],
    p_nvrtx   bigint,
    p_ncell   bigint,
    p_geoids  bigint[] DEFAULT NULL)
RETURNS bigint
LANGUAGE plpgsql
SET search_path FROM CURRENT
AS $$
DECLARE
    v_geoid bigint;
BEGIN
    IF p_bounds IS NOT NULL AND (cardinality(p_bounds) <> 6 OR array_position(p_bounds, NULL) IS NOT NULL
                                 OR 'NaN' = ANY (p_bounds) OR 'Infinity' = ANY (p_bounds) OR '-Infinity' = ANY (p_bounds)) THEN
        RAISE EXCEPTION 'bounds of a new geometry must be 6 finite numbers {xmin, ymin, zmin, xmax, ymax, zmax}, got %', p_bounds
            USING ERRCODE = 'TG102';
    END IF;
    INSERT INTO tgsis.geometry (geotype, geoname, geoids, bbox, nvrtx, ncell)
    VALUES (upper(p_geotype), p_name, p_geoids,
            CASE WHEN p_bounds IS NOT NULL THEN cube(p_bounds[1:3], p_bounds[4:6]) END,
            p_nvrtx, p_ncell)
    RETURNING geoid INTO v_geoid;
    RETURN v_geoid;
END
$$;

COMMENT ON FUNCTION tgsis.new_geometry(text, text, double precision[], bigint, bigint, bigint[]) IS
    'insert a tgsis.geometry row (bounding box from {xmin, ymin, zmin, xmax, ymax, zmax}) and return its geoid';
