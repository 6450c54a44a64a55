-- tgsis.check_static_geometry(geoid): what is wrong with a stored static (model-1) geometry (no rows: nothing).
-- Model 1's check function in the registry (tgsis.data_models), read by
-- tgsis.check_geometry: rows written by other means than the client's write
-- path may point at missing vertices or leave the bbox stale.
CREATE FUNCTION tgsis.check_static_geometry(p_geoid bigint)
RETURNS TABLE (problem text, count bigint, example text)
LANGUAGE plpgsql
STABLE
SET search_path FROM CURRENT
AS $$
DECLARE
    v_geo   record;
    v_table text;
    v_k     int;
    v_i     int;
BEGIN
    SELECT geotype, nvrtx, bbox INTO v_geo FROM tgsis.geometry WHERE geoid = p_geoid;
    RETURN QUERY SELECT 'vertex with a NaN or infinite coordinate'::text, count(*), min(vrtxid)::text
                   FROM tgsis.vrtx
                  WHERE geoid = p_geoid
                    AND (x IN ('NaN', 'Infinity', '-Infinity') OR y IN ('NaN', 'Infinity', '-Infinity')
                         OR z IN ('NaN', 'Infinity', '-Infinity'))
                 HAVING count(*) > 0;

    v_table := tgsis.simplex_table(v_geo.geotype);
    v_k := CASE v_table WHEN 'point' THEN 1 WHEN 'segment' THEN 2 WHEN 'trgl' THEN 3 ELSE 4 END;
    FOR v_i IN 1 .. v_k LOOP
        RETURN QUERY EXECUTE format(
            'SELECT %L::text, count(*), min(s.%I)::text FROM tgsis.%I s
              WHERE s.geoid = $1
                AND NOT EXISTS (SELECT FROM tgsis.vrtx v WHERE v.geoid = s.geoid AND v.vrtxid = s.%I)
             HAVING count(*) > 0',
            format('%s refers to a missing vertex (vrtxid%s)', v_table, v_i),
            CASE v_table WHEN 'point' THEN 'pointid' WHEN 'segment' THEN 'segid'
                         WHEN 'trgl' THEN 'trglid' ELSE 'tetraid' END,
            v_table, 'vrtxid' || v_i) USING p_geoid;
    END LOOP;

    -- atoms repeat a vertex at the same place; parts cover simplices that exist
    RETURN QUERY SELECT 'atom refers to a missing vertex'::text, count(*), min(a.vrtxid)::text
                   FROM tgsis.atom a
                  WHERE a.geoid = p_geoid
                    AND (NOT EXISTS (SELECT FROM tgsis.vrtx v WHERE v.geoid = a.geoid AND v.vrtxid = a.vrtxid)
                         OR NOT EXISTS (SELECT FROM tgsis.vrtx v WHERE v.geoid = a.geoid AND v.vrtxid = a.refid))
                 HAVING count(*) > 0;
    RETURN QUERY SELECT 'atom is not at the place of the vertex it repeats'::text, count(*), min(a.vrtxid)::text
                   FROM tgsis.atom a
                   JOIN tgsis.vrtx v ON v.geoid = a.geoid AND v.vrtxid = a.vrtxid
                   JOIN tgsis.vrtx r ON r.geoid = a.geoid AND r.vrtxid = a.refid
                  WHERE a.geoid = p_geoid AND (v.x, v.y, v.z) IS DISTINCT FROM (r.x, r.y, r.z)
                 HAVING count(*) > 0;
    RETURN QUERY SELECT 'part ranges overlap'::text, count(*), min(p.firstid)::text
                   FROM tgsis.part p
                  WHERE p.geoid = p_geoid
                    AND EXISTS (SELECT FROM tgsis.part q WHERE q.geoid = p.geoid AND q.firstid > p.firstid
                                                          AND q.firstid <= p.lastid)
                 HAVING count(*) > 0;

    RETURN QUERY
        SELECT 'bounding box or counts out of date (run tgsis.refresh_geometry)'::text, 1::bigint, NULL::text
          FROM (SELECT count(*) AS n,
                       CASE WHEN count(*) > 0
                            THEN cube(ARRAY[min(x), min(y), min(z)], ARRAY[max(x), max(y), max(z)]) END AS bbox
                  FROM tgsis.vrtx WHERE geoid = p_geoid) AS v
         WHERE v.n <> v_geo.nvrtx OR v.bbox IS DISTINCT FROM v_geo.bbox;
END
$$;

COMMENT ON FUNCTION tgsis.check_static_geometry(bigint) IS
    'problems of a stored static geometry: non-finite coordinates, simplices pointing at missing vertices, atoms of missing or moved vertices, overlapping part ranges, stale bbox/counts; model 1''s check function (tgsis.data_models)';
