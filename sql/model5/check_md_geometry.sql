-- tgsis.check_md_geometry(geoid): what is wrong with a stored multiply indexed G-map, in the form tgsis.check_geometry returns.
-- Model 5's check function in the registry (tgsis.data_models): the
-- conditions of tgsis.md_check (first offending dart as the example), points
-- without m finite coordinates, a stale extent, bbox or counts.
CREATE FUNCTION tgsis.check_md_geometry(p_geoid bigint)
RETURNS TABLE (problem text, count bigint, example text)
LANGUAGE plpgsql
STABLE
SET search_path FROM CURRENT
AS $$
DECLARE
    v_m smallint;
BEGIN
    SELECT g.embedding INTO v_m FROM tgsis.md_gmap g WHERE g.geoid = p_geoid;
    IF NOT FOUND THEN
        RETURN QUERY SELECT 'multiply indexed G-map geometry has no tgsis.md_gmap row'::text, 1::bigint, p_geoid::text;
        RETURN;
    END IF;
    RETURN QUERY SELECT c.problem, c.count, 'dart ' || c.darts[1] FROM tgsis.md_check(p_geoid) c;
    RETURN QUERY
        SELECT format('point without %s finite coordinates', v_m), count(*), 'vertex ' || min(v.vrtxid)
          FROM tgsis.md_vertex v
         WHERE v.geoid = p_geoid
           AND (cardinality(v.coordinate) <> v_m
                OR EXISTS (SELECT FROM unnest(v.coordinate) c WHERE c IN ('NaN', 'Infinity', '-Infinity')))
        HAVING count(*) > 0;
    RETURN QUERY
        SELECT 'extent, bounding box or counts out of date (run tgsis.refresh_geometry)'::text, 1::bigint, NULL::text
          FROM tgsis.geometry g
          JOIN tgsis.md_gmap m ON m.geoid = g.geoid
          CROSS JOIN LATERAL (SELECT count(*) AS n,
                                     CASE WHEN count(*) > 0 THEN
                                         cube(ARRAY[min(coalesce(v.coordinate[1], 0)), min(coalesce(v.coordinate[2], 0)),
                                                    min(coalesce(v.coordinate[3], 0))],
                                              ARRAY[max(coalesce(v.coordinate[1], 0)), max(coalesce(v.coordinate[2], 0)),
                                                    max(coalesce(v.coordinate[3], 0))]) END AS bbox,
                                     bool_and(m.extent IS NOT NULL AND cube(v.coordinate) <@ m.extent) AS inside
                                FROM tgsis.md_vertex v WHERE v.geoid = p_geoid) s
         WHERE g.geoid = p_geoid
           AND (g.nvrtx <> s.n OR g.bbox IS DISTINCT FROM s.bbox OR NOT coalesce(s.inside, m.extent IS NULL)
                OR g.ncell <> (SELECT count(*) FROM tgsis.md_dart d WHERE d.geoid = p_geoid));
END
$$;

COMMENT ON FUNCTION tgsis.check_md_geometry(bigint) IS
    'problems of a stored multiply indexed G-map geometry: those of tgsis.md_check, points without m finite coordinates, a stale extent, bbox or counts; model 5''s check function (tgsis.data_models)';
