-- tgsis.check_geometry(geoid): what is wrong with a stored geometry (no rows: nothing).
-- The client validates before writing; this checks rows written by other means.
-- Collections are the core's; the rest is the geometry's data model's check.
CREATE FUNCTION tgsis.check_geometry(p_geoid bigint)
RETURNS TABLE (problem text, count bigint, example text)
LANGUAGE plpgsql
STABLE
SET search_path FROM CURRENT
AS $$
DECLARE
    v_geo   record;
    v_hook  text;
BEGIN
    SELECT geotype, geoids, nvrtx, ncell, bbox, timemodel INTO v_geo FROM tgsis.geometry WHERE geoid = p_geoid;
    IF NOT FOUND THEN
        RAISE EXCEPTION 'geometry % does not exist', p_geoid USING ERRCODE = 'TG200';
    END IF;
    IF v_geo.geotype = 'GEOMETRYCOLLECTION' THEN
        RETURN QUERY SELECT 'member geometry does not exist'::text, count(*), min(m)::text
                       FROM unnest(v_geo.geoids) AS m
                      WHERE NOT EXISTS (SELECT FROM tgsis.geometry g WHERE g.geoid = m)
                     HAVING count(*) > 0;
        RETURN QUERY SELECT 'member is a GEOMETRYCOLLECTION (collections do not nest)'::text, count(*), min(g.geoid)::text
                       FROM tgsis.geometry g
                      WHERE g.geoid = ANY (v_geo.geoids) AND g.geotype = 'GEOMETRYCOLLECTION'
                     HAVING count(*) > 0;
        RETURN QUERY SELECT 'owned member not listed in geoids'::text, count(*), min(g.geoid)::text
                       FROM tgsis.geometry g
                      WHERE g.collection = p_geoid AND NOT g.geoid = ANY (v_geo.geoids)
                     HAVING count(*) > 0;
        RETURN QUERY
            SELECT 'bounding box or counts out of date (run tgsis.refresh_geometry)'::text, 1::bigint, NULL::text
              FROM (SELECT coalesce(sum(g.nvrtx), 0) AS n, coalesce(sum(g.ncell), 0) AS m,
                           CASE WHEN count(g.bbox) > 0 THEN
                               cube(ARRAY[min(cube_ll_coord(g.bbox, 1)), min(cube_ll_coord(g.bbox, 2)), min(cube_ll_coord(g.bbox, 3))],
                                    ARRAY[max(cube_ur_coord(g.bbox, 1)), max(cube_ur_coord(g.bbox, 2)), max(cube_ur_coord(g.bbox, 3))])
                           END AS bbox
                      FROM tgsis.geometry g WHERE g.geoid = ANY (v_geo.geoids)) AS u
             WHERE u.n <> v_geo.nvrtx OR u.m <> v_geo.ncell OR u.bbox IS DISTINCT FROM v_geo.bbox;
        RETURN;
    END IF;

    -- the rest is the data model's (tgsis.data_models.check_function)
    SELECT m.check_function INTO v_hook FROM tgsis.data_models m WHERE m.timemodel = v_geo.timemodel;
    RETURN QUERY EXECUTE format('SELECT c.problem, c.count, c.example FROM tgsis.%I($1) c', v_hook) USING p_geoid;
END
$$;

COMMENT ON FUNCTION tgsis.check_geometry(bigint) IS
    'problems of a stored geometry: missing, nested or unlisted members and stale bbox/counts of a collection; the others by their data model''s check function (tgsis.data_models: tgsis.check_static_geometry, tgsis.check_temporal_geometry)';
