-- tgsis.check_md_geometry(geoid): what is wrong with a stored multiply indexed G-map, in the form tgsis.check_geometry returns.
-- Model 5's check function in the registry (tgsis.data_models): the
-- conditions of tgsis.md_check (first offending dart as the example), points
-- without m finite coordinates, a stale extent, bbox or counts (the boxes
-- are those tgsis.md_extent computes, of the points without a NaN).
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
    -- the extent and bbox as tgsis.md_extent computes them: of the points without a NaN coordinate, equal (a
    -- stored box with a NaN, as before 0.3.0 computed, is stale: the cube type's = may take it for any box)
    RETURN QUERY
        SELECT 'extent, bounding box or counts out of date (run tgsis.refresh_geometry)'::text, 1::bigint, NULL::text
          FROM tgsis.geometry g
          JOIN tgsis.md_gmap m ON m.geoid = g.geoid
          CROSS JOIN LATERAL (SELECT count(*) AS n FROM tgsis.md_vertex v WHERE v.geoid = p_geoid) s
          CROSS JOIN LATERAL (SELECT CASE WHEN count(*) > 0 THEN
                                         cube(ARRAY[min(coalesce(v.coordinate[1], 0)), min(coalesce(v.coordinate[2], 0)),
                                                    min(coalesce(v.coordinate[3], 0))],
                                              ARRAY[max(coalesce(v.coordinate[1], 0)), max(coalesce(v.coordinate[2], 0)),
                                                    max(coalesce(v.coordinate[3], 0))]) END AS bbox
                                FROM tgsis.md_vertex v
                               WHERE v.geoid = p_geoid AND NOT 'NaN'::double precision = ANY (v.coordinate)) b
          CROSS JOIN LATERAL (SELECT CASE WHEN count(*) > 0 THEN cube(array_agg(lo ORDER BY i), array_agg(hi ORDER BY i)) END AS extent
                                FROM (SELECT u.i, min(u.x) AS lo, max(u.x) AS hi
                                        FROM tgsis.md_vertex v, unnest(v.coordinate) WITH ORDINALITY AS u (x, i)
                                       WHERE v.geoid = p_geoid AND NOT 'NaN'::double precision = ANY (v.coordinate)
                                       GROUP BY u.i) a) e
         WHERE g.geoid = p_geoid
           AND (g.nvrtx <> s.n OR g.bbox IS DISTINCT FROM b.bbox OR m.extent IS DISTINCT FROM e.extent
                OR g.bbox::text LIKE '%NaN%' OR m.extent::text LIKE '%NaN%'
                OR g.ncell <> (SELECT count(*) FROM tgsis.md_dart d WHERE d.geoid = p_geoid));
END
$$;

COMMENT ON FUNCTION tgsis.check_md_geometry(bigint) IS
    'problems of a stored multiply indexed G-map geometry: those of tgsis.md_check, points without m finite coordinates, a stale extent, bbox or counts; model 5''s check function (tgsis.data_models)';
