-- tgsis.md_extent(geoid): bounding box and counts of a multiply indexed G-map (model 5).
-- Model 5's extent function in the registry (tgsis.data_models), read by
-- tgsis.refresh_geometry: the 3D box of tgsis.geometry is of the first
-- three axes (0 where there are fewer); nvrtx counts points, ncell darts.
-- It also brings tgsis.md_gmap.extent (every axis) up to date. Both boxes
-- are of the points without a NaN coordinate, as tgsis.md_vertices_in_box
-- finds none of those: a NaN has no place in the float8 order the cube
-- type's index uses (counted as the largest value, it made md_in_box's
-- answer hang on the plan). A G-map none of whose points has a position
-- has neither (NULL): tgsis.md_in_box and tgsis.geometries_in_box find it
-- in no box. tgsis.db.multidim computes them alike at insert.
CREATE FUNCTION tgsis.md_extent(p_geoid bigint)
RETURNS TABLE (bbox cube, nvrtx bigint, ncell bigint)
LANGUAGE plpgsql
VOLATILE
SET search_path FROM CURRENT
AS $$
BEGIN
    SELECT count(*) INTO ncell FROM tgsis.md_dart d WHERE d.geoid = p_geoid;
    SELECT count(*) INTO nvrtx FROM tgsis.md_vertex v WHERE v.geoid = p_geoid;
    SELECT CASE WHEN count(*) > 0 THEN
                cube(ARRAY[min(coalesce(v.coordinate[1], 0)), min(coalesce(v.coordinate[2], 0)), min(coalesce(v.coordinate[3], 0))],
                     ARRAY[max(coalesce(v.coordinate[1], 0)), max(coalesce(v.coordinate[2], 0)), max(coalesce(v.coordinate[3], 0))])
           END
      INTO bbox
      FROM tgsis.md_vertex v
     WHERE v.geoid = p_geoid AND NOT 'NaN'::double precision = ANY (v.coordinate);  -- NaN = NaN for float8's equality
    UPDATE tgsis.md_gmap g SET extent = e.extent
      FROM (SELECT CASE WHEN count(*) > 0 THEN cube(array_agg(lo ORDER BY i), array_agg(hi ORDER BY i)) END AS extent
              FROM (SELECT u.i, min(u.x) AS lo, max(u.x) AS hi
                      FROM tgsis.md_vertex v, unnest(v.coordinate) WITH ORDINALITY AS u (x, i)
                     WHERE v.geoid = p_geoid AND NOT 'NaN'::double precision = ANY (v.coordinate)
                     GROUP BY u.i) a) e
     WHERE g.geoid = p_geoid
       AND (g.extent IS DISTINCT FROM e.extent OR g.extent::text LIKE '%NaN%');  -- (cube's = may take a NaN for any value)
    RETURN NEXT;
END
$$;

COMMENT ON FUNCTION tgsis.md_extent(bigint) IS
    'bbox of the first three axes, number of points and of darts of a multiply indexed G-map (model 5), and its extent over every axis (tgsis.md_gmap.extent) brought up to date; both of the points without a NaN coordinate (NULL when there is none); model 5''s extent function (tgsis.data_models)';
