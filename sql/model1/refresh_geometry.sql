-- tgsis.refresh_geometry(geoid): recompute a geometry's bounding box and counts from its rows.
-- The client's write path sets them itself; this is for edits made with plain SQL.
CREATE FUNCTION tgsis.refresh_geometry(p_geoid bigint)
RETURNS tgsis.geometry
LANGUAGE plpgsql
SET search_path FROM CURRENT
AS $$
DECLARE
    v_geotype text;
    v_ncell   bigint;
    v_row     tgsis.geometry;
BEGIN
    SELECT geotype INTO v_geotype FROM tgsis.geometry WHERE geoid = p_geoid FOR UPDATE;
    IF NOT FOUND THEN
        RAISE EXCEPTION 'geometry % does not exist', p_geoid
            USING ERRCODE = 'TG200', HINT = 'SELECT geoid FROM tgsis.geometry lists the stored geometries';
    END IF;

    IF v_geotype = 'GEOMETRYCOLLECTION' THEN
        UPDATE tgsis.geometry g
           SET bbox = m.bbox, nvrtx = m.nvrtx, ncell = m.ncell
          FROM (SELECT CASE WHEN count(bbox) > 0 THEN  -- members without vertices have no bbox
                           cube(ARRAY[min(cube_ll_coord(bbox, 1)), min(cube_ll_coord(bbox, 2)), min(cube_ll_coord(bbox, 3))],
                                ARRAY[max(cube_ur_coord(bbox, 1)), max(cube_ur_coord(bbox, 2)), max(cube_ur_coord(bbox, 3))])
                       END AS bbox,
                       coalesce(sum(nvrtx), 0) AS nvrtx, coalesce(sum(ncell), 0) AS ncell
                  FROM tgsis.geometry
                 WHERE geoid = ANY ((SELECT geoids FROM tgsis.geometry WHERE geoid = p_geoid)::bigint[])) AS m
         WHERE g.geoid = p_geoid
        RETURNING g.* INTO v_row;
        RETURN v_row;
    END IF;

    EXECUTE format('SELECT count(*) FROM tgsis.%I WHERE geoid = $1', tgsis.simplex_table(v_geotype))
       INTO v_ncell USING p_geoid;
    UPDATE tgsis.geometry g
       SET bbox = v.bbox, nvrtx = v.n, ncell = v_ncell
      FROM (SELECT count(*) AS n,
                   CASE WHEN count(*) > 0
                        THEN cube(ARRAY[min(x), min(y), min(z)], ARRAY[max(x), max(y), max(z)]) END AS bbox
              FROM tgsis.vrtx WHERE geoid = p_geoid) AS v
     WHERE g.geoid = p_geoid
    RETURNING g.* INTO v_row;
    RETURN v_row;
END
$$;

COMMENT ON FUNCTION tgsis.refresh_geometry(bigint) IS
    'recompute bbox, nvrtx and ncell of a geometry from its vertex and simplex rows (after edits with plain SQL); returns the row';
