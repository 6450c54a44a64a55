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
                           -- the members' union as tgsis.refresh_geometry takes it, compared by the coordinates
                           -- as stored (cube's = reads them through the least and greatest of a corner pair by <
                           -- and >, which hides a NaN)
                           CASE WHEN count(g.bbox) > 0 THEN
                               ARRAY[min(least(cube_coord(g.bbox, 1), cube_coord(g.bbox, 4))),
                                     min(least(cube_coord(g.bbox, 2), cube_coord(g.bbox, 5))),
                                     min(least(cube_coord(g.bbox, 3), cube_coord(g.bbox, 6))),
                                     max(greatest(cube_coord(g.bbox, 1), cube_coord(g.bbox, 4))),
                                     max(greatest(cube_coord(g.bbox, 2), cube_coord(g.bbox, 5))),
                                     max(greatest(cube_coord(g.bbox, 3), cube_coord(g.bbox, 6)))]
                           END AS corners
                      FROM tgsis.geometry g WHERE g.geoid = ANY (v_geo.geoids)) AS u
             WHERE u.n <> v_geo.nvrtx OR u.m <> v_geo.ncell
                OR u.corners IS DISTINCT FROM
                   (SELECT array_agg(cube_coord(v_geo.bbox, d) ORDER BY d)
                      FROM generate_series(1, 2 * cube_dim(v_geo.bbox)) AS d);
        RETURN;
    END IF;

    -- the rest is the data model's (tgsis.data_models.check_function)
    SELECT m.check_function INTO v_hook FROM tgsis.data_models m WHERE m.timemodel = v_geo.timemodel;
    RETURN QUERY EXECUTE format('SELECT c.problem, c.count, c.example FROM tgsis.%I($1) c', v_hook) USING p_geoid;
END
$$;

COMMENT ON FUNCTION tgsis.check_geometry(bigint) IS
    'problems of a stored geometry: missing, nested or unlisted members and stale bbox/counts of a collection; the others by their data model''s check function (tgsis.data_models: tgsis.check_static_geometry, tgsis.check_temporal_geometry)';
