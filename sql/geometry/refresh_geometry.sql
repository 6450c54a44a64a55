-- tgsis.refresh_geometry(geoid): recompute a geometry's bounding box and counts from its rows.
-- The client's write path sets them itself; this is for edits made with plain SQL.
-- Returns the new values (not the table's row type: once model 1 is
-- versioned, tgsis.geometry is a view and its storage type has more columns).
CREATE FUNCTION tgsis.refresh_geometry(p_geoid bigint)
RETURNS TABLE (geoid bigint, bbox cube, nvrtx bigint, ncell bigint)
LANGUAGE plpgsql
SET search_path FROM CURRENT
AS $$
#variable_conflict use_column
DECLARE
    v_geotype text;
    v_model   text;
    v_bbox    cube;
    v_nvrtx   bigint;
    v_ncell   bigint;
    v_hook    text;
BEGIN
    SELECT g.geotype, g.timemodel INTO v_geotype, v_model FROM tgsis.geometry g WHERE g.geoid = p_geoid FOR UPDATE;
    IF NOT FOUND THEN
        RAISE EXCEPTION 'geometry % does not exist', p_geoid
            USING ERRCODE = 'TG200', HINT = 'SELECT geoid FROM tgsis.geometry lists the stored geometries';
    END IF;

    IF v_geotype = 'GEOMETRYCOLLECTION' THEN
        -- members without vertices have no bbox; a member's corners are taken as stored (cube_coord), each axis's
        -- least and greatest by float8's order (least/greatest, min/max: NaN after every number), as a box is
        -- measured from vertices: cube_ll_coord / cube_ur_coord compare by < and >, which a NaN fails both ways,
        -- and so read (0, 0, 0),(NaN, 1, 1) as (NaN, 0, 0),(NaN, 1, 1), losing the member's finite low corner
        SELECT CASE WHEN count(m.bbox) > 0 THEN
                    cube(ARRAY[min(least(cube_coord(m.bbox, 1), cube_coord(m.bbox, 4))),
                               min(least(cube_coord(m.bbox, 2), cube_coord(m.bbox, 5))),
                               min(least(cube_coord(m.bbox, 3), cube_coord(m.bbox, 6)))],
                         ARRAY[max(greatest(cube_coord(m.bbox, 1), cube_coord(m.bbox, 4))),
                               max(greatest(cube_coord(m.bbox, 2), cube_coord(m.bbox, 5))),
                               max(greatest(cube_coord(m.bbox, 3), cube_coord(m.bbox, 6)))])
               END,
               coalesce(sum(m.nvrtx), 0), coalesce(sum(m.ncell), 0)
          INTO v_bbox, v_nvrtx, v_ncell
          FROM tgsis.geometry m
         WHERE m.geoid = ANY ((SELECT c.geoids FROM tgsis.geometry c WHERE c.geoid = p_geoid)::bigint[]);
    ELSE
        -- the geometry's data model computes them from its own tables (tgsis.data_models.extent_function)
        SELECT m.extent_function INTO v_hook FROM tgsis.data_models m WHERE m.timemodel = v_model;
        EXECUTE format('SELECT e.bbox, e.nvrtx, e.ncell FROM tgsis.%I($1) e', v_hook)
           INTO v_bbox, v_nvrtx, v_ncell USING p_geoid;
    END IF;
    UPDATE tgsis.geometry g SET bbox = v_bbox, nvrtx = v_nvrtx, ncell = v_ncell WHERE g.geoid = p_geoid;
    RETURN QUERY SELECT p_geoid, v_bbox, v_nvrtx, v_ncell;
END
$$;

COMMENT ON FUNCTION tgsis.refresh_geometry(bigint) IS
    'recompute bbox, nvrtx and ncell of a geometry from its rows (after edits with plain SQL): a collection from its members, the others by their data model''s extent function (tgsis.data_models); returns them';
