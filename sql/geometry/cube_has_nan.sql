-- tgsis.cube_has_nan(box): whether a box (cube) has a NaN among its corners' coordinates.
-- The predicate of the GiST indexes over boxes (tgsis.geometry's bbox, model 5's
-- extents): those indexes leave such boxes out, and the queries that read them
-- (tgsis.geometries_in_box, tgsis.md_in_box) carry the same predicate, so that a
-- box with a NaN is in no box whatever the plan. A GiST key with a NaN spoils
-- the index's inner boxes (the cube type's union takes the least and greatest
-- coordinate by < and >, which a NaN fails both ways, so the union keeps
-- whichever operand came second): an index scan missed valid boxes a sequential
-- scan found (docs/storage.md, "NaN coordinates and the box indexes"). An
-- infinity is ordered and harmless. IMMUTABLE (an index predicate); executable
-- by PUBLIC: it runs as whoever writes the indexed tables.
CREATE FUNCTION tgsis.cube_has_nan(p_box cube)
RETURNS boolean
LANGUAGE sql
IMMUTABLE
STRICT
PARALLEL SAFE
SET search_path FROM CURRENT
AS $$
    -- the 2m coordinates as stored (cube_coord; cube_ll_coord and cube_ur_coord take the least and greatest of a
    -- corner pair, which hides a NaN); NaN = NaN for float8's equality
    SELECT EXISTS (SELECT FROM generate_series(1, 2 * cube_dim(p_box)) AS d
                    WHERE cube_coord(p_box, d) = 'NaN'::double precision)
$$;

COMMENT ON FUNCTION tgsis.cube_has_nan(cube) IS
    'whether a box (cube) has a NaN coordinate at a corner; the predicate the GiST indexes over boxes (tgsis.geometry.bbox, tgsis.md_gmap.extent) leave such boxes out by, and that tgsis.geometries_in_box and tgsis.md_in_box carry (a box with a NaN is in no box)';
