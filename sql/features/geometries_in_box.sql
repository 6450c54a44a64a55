-- tgsis.geometries_in_box(xmin, ymin, zmin, xmax, ymax, zmax): geometries whose bounding box meets the box.
CREATE FUNCTION tgsis.geometries_in_box(
    p_xmin double precision, p_ymin double precision, p_zmin double precision,
    p_xmax double precision, p_ymax double precision, p_zmax double precision)
RETURNS SETOF bigint
LANGUAGE sql
STABLE
PARALLEL SAFE
SET search_path FROM CURRENT
AS $$
    SELECT geoid
      FROM tgsis.geometry
     WHERE bbox && cube(ARRAY[p_xmin, p_ymin, p_zmin], ARRAY[p_xmax, p_ymax, p_zmax])
       AND NOT tgsis.cube_has_nan(bbox)  -- the index's predicate: a box with a NaN is in no box, by any plan
     ORDER BY geoid
$$;

COMMENT ON FUNCTION tgsis.geometries_in_box(double precision, double precision, double precision,
                                            double precision, double precision, double precision) IS
    'ids of the geometries whose 3D bounding box intersects the given box (GiST index scan on tgsis.geometry.bbox); a bounding box with a NaN coordinate (a vertex with a NaN, which tgsis.check_geometry reports) meets no box';
