-- tgsis.md_vertices_in_box(geoid, axes, low, high): the points of a multiply indexed G-map inside a box over some of its axes.
-- E.g. the part of a horizon's interpretations between knowledge 1 and 2
-- over an x-y window. The points are GiST-indexed as cubes
-- (md_vertex_point_idx); the box is unbounded on the axes not given. An
-- axis the G-map does not have is refused (TG100, naming it and the G-map's
-- axes) rather than answered with no point. The box is closed (a point on
-- its face is inside). A point with a NaN coordinate is in no box: it has
-- no position (tgsis.check_md_geometry reports it), and the cube type's
-- comparisons would otherwise put it inside any box on that axis by a
-- sequential scan but not always by the index (among 50,000 points, one of
-- NaNs only was found by a scan and missed by the index: the answer hung on
-- the plan; tests/test_gmap_multidim.py forces both plans).
CREATE FUNCTION tgsis.md_vertices_in_box(p_geoid bigint, p_axes text[], p_low double precision[], p_high double precision[])
RETURNS TABLE (vrtxid bigint, coordinate double precision[])
LANGUAGE plpgsql
STABLE
SET search_path FROM CURRENT
AS $$
DECLARE
    v_box  cube;
    v_axes text[];
BEGIN
    SELECT tgsis.md_query_box(g.axes, p_axes, p_low, p_high), g.axes INTO v_box, v_axes FROM tgsis.md_gmap g WHERE g.geoid = p_geoid;
    IF NOT FOUND THEN
        RAISE EXCEPTION 'geometry % is not a stored multiply indexed G-map', p_geoid
            USING ERRCODE = 'TG200', HINT = 'SELECT geoid FROM tgsis.md_gmap lists them';
    END IF;
    IF v_box IS NULL THEN   -- the box is well formed (md_query_box checked it): an axis is not the G-map's
        RAISE EXCEPTION 'multiply indexed G-map % has no axis %', p_geoid,
                quote_literal(left((SELECT a FROM unnest(p_axes) a WHERE a <> ALL (v_axes) LIMIT 1), 100))
            USING ERRCODE = 'TG100', DETAIL = format('Its axes: %s.', array_to_string(v_axes, ', ')),
                  HINT = 'p_axes names some of the G-map''s axes (SELECT axes FROM tgsis.md_gmap WHERE geoid = ...)';
    END IF;
    RETURN QUERY
    SELECT v.vrtxid, v.coordinate FROM tgsis.md_vertex v
     WHERE cube(v.coordinate) <@ v_box AND v.geoid = p_geoid
       AND NOT 'NaN'::double precision = ANY (v.coordinate)  -- NaN = NaN for float8's equality
     ORDER BY v.vrtxid;
END
$$;

COMMENT ON FUNCTION tgsis.md_vertices_in_box(bigint, text[], double precision[], double precision[]) IS
    'model 5: the points (vrtxid, coordinate) of a multiply indexed G-map inside a box over some of its axes (unbounded on the others, closed: a point on a face is inside; a point with a NaN coordinate is in none), by GiST index';
