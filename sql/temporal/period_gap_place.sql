-- tgsis.period_gap_place(geoid, model, nodeid, timem): where a gap of a topology change lies, in words for messages.
-- A node of a surface (model 3) is named by its id and period; a point of a
-- G-map (model 4) by the first dart on it, as the G-map checks name darts.
CREATE FUNCTION tgsis.period_gap_place(p_geoid bigint, p_model text, p_nodeid bigint, p_timem double precision)
RETURNS text
LANGUAGE plpgsql
STABLE
SET search_path FROM CURRENT
AS $$
BEGIN
    IF p_model = 'GMAP' THEN
        RETURN format('dart %s (node %s) of the period from %s',
                      (SELECT min(d.dartid) FROM tgsis.gmap_dart d WHERE d.geoid = p_geoid AND d.nodeid = p_nodeid), p_nodeid, p_timem);
    END IF;
    RETURN format('node %s of the period from %s', p_nodeid, p_timem);
END
$$;

COMMENT ON FUNCTION tgsis.period_gap_place(bigint, text, bigint, double precision) IS
    'the words naming where a gap of a topology change lies: node and period (model 3), dart, node and period (model 4); used by tgsis.period_gaps';
