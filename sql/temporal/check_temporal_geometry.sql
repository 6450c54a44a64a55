-- tgsis.check_temporal_geometry(geoid): what is wrong with the rows of a model-2 or model-3 geometry (no rows: nothing).
-- The client writes consistent rows; this checks rows edited with plain SQL,
-- which the snapshot would otherwise silently misread (a node without a
-- position at an instant drops out of the snapshot, a gap between periods
-- makes the surface vanish there, a period starting away from the end of
-- the one before makes it jump).
CREATE FUNCTION tgsis.check_temporal_geometry(p_geoid bigint)
RETURNS TABLE (problem text, count bigint, example text)
LANGUAGE plpgsql
STABLE
SET extra_float_digits = 1  -- its examples name instants and periods exactly, whatever the session's setting
AS $$
DECLARE
    v_geo record;
BEGIN
    SELECT timemodel, nvrtx, ncell, bbox INTO v_geo FROM tgsis.geometry WHERE geoid = p_geoid;
    IF NOT FOUND THEN
        RAISE EXCEPTION 'geometry % does not exist', p_geoid USING ERRCODE = 'TG200';
    END IF;
    IF v_geo.timemodel NOT IN ('INSTANTS', 'EVOLVING') THEN   -- the other models' rows are checked by their own hooks
        PERFORM tgsis.no_model_rule(v_geo.timemodel, 'tgsis.check_temporal_geometry', '{INSTANTS,EVOLVING}');
    END IF;
    IF v_geo.timemodel = 'INSTANTS' THEN
        RETURN QUERY SELECT 'vertex or triangle at an instant not in tgsis.times'::text, count(*), min(r.times)::text
                       FROM (SELECT v.times FROM tgsis.times_vrtx v WHERE v.geoid = p_geoid
                             UNION ALL SELECT c.times FROM tgsis.times_trgl c WHERE c.geoid = p_geoid) r
                      WHERE NOT EXISTS (SELECT FROM tgsis.times i WHERE i.geoid = p_geoid AND i.times = r.times)
                     HAVING count(*) > 0;
        RETURN QUERY SELECT 'triangle refers to a missing vertex of its instant'::text, count(*),
                            min(format('instant %s, trglid %s', c.times, c.trglid))
                       FROM tgsis.times_trgl c
                      WHERE c.geoid = p_geoid
                        AND EXISTS (SELECT FROM unnest(ARRAY[c.vrtxid1, c.vrtxid2, c.vrtxid3]) AS k(id)
                                     WHERE NOT EXISTS (SELECT FROM tgsis.times_vrtx v
                                                        WHERE v.geoid = p_geoid AND v.times = c.times AND v.vrtxid = k.id))
                     HAVING count(*) > 0;
        RETURN QUERY SELECT 'vertex with a NaN or infinite coordinate'::text, count(*),
                            min(format('instant %s, vrtxid %s', v.times, v.vrtxid))
                       FROM tgsis.times_vrtx v
                      WHERE v.geoid = p_geoid
                        AND ('NaN' IN (v.x, v.y, v.z) OR 'Infinity' IN (abs(v.x), abs(v.y), abs(v.z)))
                     HAVING count(*) > 0;
    ELSIF v_geo.timemodel = 'EVOLVING' THEN
        RETURN QUERY SELECT 'geometry instant of a period not in tgsis.timem'::text, count(*), min(t.timem)::text
                       FROM tgsis.timet t
                      WHERE t.geoid = p_geoid AND NOT EXISTS (SELECT FROM tgsis.timem m WHERE m.geoid = p_geoid AND m.timem = t.timem)
                     HAVING count(*) > 0;
        RETURN QUERY SELECT 'topology period without a geometry instant at its start'::text, count(*), min(m.timem)::text
                       FROM tgsis.timem m
                      WHERE m.geoid = p_geoid
                        AND NOT EXISTS (SELECT FROM tgsis.timet t WHERE t.geoid = p_geoid AND t.timem = m.timem AND t.timet = m.timem)
                     HAVING count(*) > 0;
        RETURN QUERY SELECT 'topology period does not end where the next one starts'::text, count(*), min(p.timem)::text
                       FROM (SELECT m.timem, lead(m.timem) OVER (ORDER BY m.timem) AS next,
                                    (SELECT max(t.timet) FROM tgsis.timet t WHERE t.geoid = p_geoid AND t.timem = m.timem) AS last
                               FROM tgsis.timem m WHERE m.geoid = p_geoid) p
                      WHERE p.next IS NOT NULL AND p.last IS DISTINCT FROM p.next
                     HAVING count(*) > 0;
        RETURN QUERY SELECT 'shape jumps at a topology instant: the period''s first shape lies farther than the tolerance from the last shape before it (tgsis.period_gaps)'::text,
                            count(*), (array_agg(format('period from %s: %s apart at %s', g.timem, g.gap, g.place) ORDER BY g.timem))[1]
                       FROM tgsis.period_gaps(p_geoid) g
                      WHERE g.gap > g.tolerance
                     HAVING count(*) > 0;
        RETURN QUERY SELECT 'node without a position at a geometry instant of its period'::text, count(*),
                            min(format('nodeid %s at %s', n.nodeid, t.timet))
                       FROM tgsis.node n
                       JOIN tgsis.timet t ON t.geoid = p_geoid AND t.timem = n.timem
                      WHERE n.geoid = p_geoid
                        AND NOT EXISTS (SELECT FROM tgsis.d4dvrtx v WHERE v.geoid = p_geoid AND v.timem = n.timem
                                                                      AND v.timet = t.timet AND v.nodeid = n.nodeid)
                     HAVING count(*) > 0;
        RETURN QUERY SELECT 'position of a node or at an instant its period does not have'::text, count(*),
                            min(format('nodeid %s at %s', v.nodeid, v.timet))
                       FROM tgsis.d4dvrtx v
                      WHERE v.geoid = p_geoid
                        AND (NOT EXISTS (SELECT FROM tgsis.node n WHERE n.geoid = p_geoid AND n.timem = v.timem AND n.nodeid = v.nodeid)
                             OR NOT EXISTS (SELECT FROM tgsis.timet t WHERE t.geoid = p_geoid AND t.timem = v.timem AND t.timet = v.timet))
                     HAVING count(*) > 0;
        RETURN QUERY SELECT 'triangle refers to a missing node of its period'::text, count(*),
                            min(format('period %s, trglid %s', c.timem, c.trglid))
                       FROM tgsis.d4dtrgl c
                      WHERE c.geoid = p_geoid
                        AND EXISTS (SELECT FROM unnest(ARRAY[c.nodeid1, c.nodeid2, c.nodeid3]) AS k(id)
                                     WHERE NOT EXISTS (SELECT FROM tgsis.node n
                                                        WHERE n.geoid = p_geoid AND n.timem = c.timem AND n.nodeid = k.id))
                     HAVING count(*) > 0;
        RETURN QUERY SELECT 'node position with a NaN or infinite coordinate'::text, count(*),
                            min(format('nodeid %s at %s', v.nodeid, v.timet))
                       FROM tgsis.d4dvrtx v
                      WHERE v.geoid = p_geoid
                        AND ('NaN' IN (v.x, v.y, v.z) OR 'Infinity' IN (abs(v.x), abs(v.y), abs(v.z)))
                     HAVING count(*) > 0;
    END IF;
    RETURN QUERY
        SELECT 'bounding box or counts out of date (run tgsis.refresh_geometry)'::text, 1::bigint, NULL::text
          FROM (SELECT CASE v_geo.timemodel
                           WHEN 'INSTANTS' THEN (SELECT count(*) FROM tgsis.times_vrtx v WHERE v.geoid = p_geoid)
                           ELSE (SELECT count(*) FROM tgsis.node n WHERE n.geoid = p_geoid) END AS n,
                       CASE v_geo.timemodel
                           WHEN 'INSTANTS' THEN (SELECT count(*) FROM tgsis.times_trgl c WHERE c.geoid = p_geoid)
                           ELSE (SELECT count(*) FROM tgsis.d4dtrgl c WHERE c.geoid = p_geoid) END AS m,
                       (SELECT CASE WHEN count(*) > 0 THEN cube(ARRAY[min(x), min(y), min(z)], ARRAY[max(x), max(y), max(z)]) END
                          FROM (SELECT v.x, v.y, v.z FROM tgsis.times_vrtx v WHERE v.geoid = p_geoid
                                UNION ALL SELECT v.x, v.y, v.z FROM tgsis.d4dvrtx v WHERE v.geoid = p_geoid) xyz) AS bbox) s
         WHERE s.n <> v_geo.nvrtx OR s.m <> v_geo.ncell OR s.bbox IS DISTINCT FROM v_geo.bbox;
END
$$;

COMMENT ON FUNCTION tgsis.check_temporal_geometry(bigint) IS
    'problems of the rows of a model-2 or model-3 geometry: orphan instants, triangles pointing at missing vertices or nodes, nodes missing a position at an instant, periods that do not follow each other, shapes that jump at a topology instant, non-finite coordinates, stale bbox/counts';
