-- tgsis.gmap_check(geoid): the conditions of an n-G-map and of its periods, with the offending darts (no rows: valid).
-- The conditions every G-map model shares (tgsis.gmap_conditions: (i)-(iii),
-- one point per 0-cell, rows that refer to darts), and model 4's own: every
-- involution keeps a dart in its topology period (the closure of the
-- partition D0..Dk, checked by tgsis.gmap_conditions), darts of nodes and
-- periods that exist. darts lists the first offending darts (at most 20),
-- count all of them.
-- Darts stored in chunks (docs/storage.md, "G-maps"): the periods and node
-- ranges of the darts are read from the chunk arrays the caller sees (one
-- row per chunk version, its timem and nodeid arrays unnested together, a
-- node its vbase plus the relative ref or its _wide value), not from the
-- face, which decodes every column of every slot. Read as the caller, when
-- tgsis.gmap_chunk_arrays_sql gives the chunk statement (its checks: both
-- tables in chunks, the chunk tables readable; its viewing set), with the
-- faces' visibility test (tgsis.visible_versions) and snapshot guard; else
-- through the face.
CREATE FUNCTION tgsis.gmap_check(p_geoid bigint)
RETURNS TABLE (problem text, count bigint, darts bigint[])
LANGUAGE plpgsql
STABLE
SET search_path FROM CURRENT
AS $$
DECLARE
    v_n     smallint;
    v_first double precision;
    v_last  double precision;
    v_lo    bigint;
    v_hi    bigint;
    v_dense boolean;
    v_chunks record;
    v_times double precision[];
    v_los   bigint[];
    v_his   bigint[];
BEGIN
    SELECT g.dimension INTO v_n FROM tgsis.gmap g WHERE g.geoid = p_geoid;
    IF NOT FOUND THEN
        RAISE EXCEPTION 'geometry % is not a stored G-map', p_geoid
            USING ERRCODE = 'TG200', HINT = 'SELECT geoid FROM tgsis.gmap lists the stored G-maps';
    END IF;
    RETURN QUERY SELECT * FROM tgsis.gmap_conditions(p_geoid, v_n, 'tgsis.gmap_dart', 'tgsis.gmap_alpha', 'nodeid', 'timem');
    -- the darts' nodes and periods exist. Proved without a join when, in
    -- each period the darts lie in, the period exists and its nodes are
    -- numbered densely (the key makes them unique in a period) over a range
    -- that holds the darts' nodes, as tgsis.insert_gmap numbers them: an
    -- aggregate over the darts (grouped by period only when they lie in
    -- several) and one over the nodes.
    SELECT * INTO v_chunks FROM tgsis.gmap_chunk_arrays_sql('tgsis.gmap_dart', 'tgsis.gmap_alpha', 'nodeid', 'timem');
    IF v_chunks.arrays IS NOT NULL THEN
        -- each period's node range from the chunk arrays (a hole: a NULL timem, skipped), periods ascending
        EXECUTE format('SELECT array_agg(d.t ORDER BY d.t), array_agg(d.lo ORDER BY d.t), array_agg(d.hi ORDER BY d.t)
                   FROM (SELECT u.t, min(coalesce(c.vbase + u.r, u.w)) AS lo, max(coalesce(c.vbase + u.r, u.w)) AS hi
                           FROM tgsis.gmap_dart_chunk c
                          CROSS JOIN LATERAL unnest(c.timem, c.nodeid, c.nodeid_wide) AS u (t, r, w)
                          WHERE (SELECT tgsis.chunk_snapshot_guard(''tgsis.gmap_dart_chunk''::regclass)) AND c.geoid = $1
                            AND ($2 IS NULL OR (%s))
                            AND u.t IS NOT NULL
                          GROUP BY u.t) AS d', tgsis.visible_versions('c', '$2'))
           INTO v_times, v_los, v_his USING p_geoid, v_chunks.dartset;
        v_first := v_times[1];
        v_last := v_times[cardinality(v_times)];
        SELECT min(x), max(y) INTO v_lo, v_hi FROM unnest(v_los, v_his) AS u (x, y);
    ELSE
        SELECT min(g.timem), max(g.timem), min(g.nodeid), max(g.nodeid) INTO v_first, v_last, v_lo, v_hi
          FROM tgsis.gmap_dart g WHERE g.geoid = p_geoid;
    END IF;
    IF v_first IS NULL THEN
        RETURN;   -- no darts
    END IF;
    IF v_first = v_last THEN
        v_dense := (SELECT coalesce(count(*) = max(g.nodeid) - min(g.nodeid) + 1 AND min(g.nodeid) <= v_lo AND max(g.nodeid) >= v_hi, false)
                      FROM tgsis.gmap_node g WHERE g.geoid = p_geoid AND g.timem = v_first)
                   AND EXISTS (SELECT FROM tgsis.gmap_timem m WHERE m.geoid = p_geoid AND m.timem = v_first);
    ELSE
        IF v_times IS NULL THEN
            SELECT array_agg(g.timem), array_agg(g.lo), array_agg(g.hi) INTO v_times, v_los, v_his
              FROM (SELECT g.timem, min(g.nodeid) AS lo, max(g.nodeid) AS hi
                      FROM tgsis.gmap_dart g WHERE g.geoid = p_geoid GROUP BY g.timem) AS g;
        END IF;
        v_dense := (SELECT bool_and(coalesce(m.timem IS NOT NULL AND n.nodes = n.hi - n.lo + 1 AND d.lo >= n.lo AND d.hi <= n.hi, false))
                      FROM unnest(v_times, v_los, v_his) AS d (timem, lo, hi)
                      LEFT JOIN (SELECT g.timem, count(*) AS nodes, min(g.nodeid) AS lo, max(g.nodeid) AS hi
                                   FROM tgsis.gmap_node g WHERE g.geoid = p_geoid GROUP BY g.timem) AS n ON n.timem = d.timem
                      LEFT JOIN tgsis.gmap_timem m ON m.geoid = p_geoid AND m.timem = d.timem);
    END IF;
    IF v_dense THEN
        RETURN;
    END IF;
    -- otherwise the darts that fail, by keyed joins (only those are kept and sorted)
    RETURN QUERY
        SELECT v.problem, v.count, v.darts
          FROM (SELECT count(*) FILTER (WHERE f.no_node) AS nodes,
                       (array_agg(f.dartid ORDER BY f.dartid) FILTER (WHERE f.no_node))[1:20] AS node_darts,
                       count(*) FILTER (WHERE f.no_period) AS periods,
                       (array_agg(f.dartid ORDER BY f.dartid) FILTER (WHERE f.no_period))[1:20] AS period_darts
                  FROM (SELECT d.dartid, n.nodeid IS NULL AS no_node, m.timem IS NULL AS no_period
                          FROM tgsis.gmap_dart d
                          LEFT JOIN tgsis.gmap_node n ON n.geoid = d.geoid AND n.timem = d.timem AND n.nodeid = d.nodeid
                          LEFT JOIN tgsis.gmap_timem m ON m.geoid = d.geoid AND m.timem = d.timem
                         WHERE d.geoid = p_geoid AND (n.nodeid IS NULL OR m.timem IS NULL)) AS f) AS s
         CROSS JOIN LATERAL (VALUES (1, 'dart of a node missing from its topology period', s.nodes, s.node_darts),
                                    (2, 'dart of a topology period that does not exist', s.periods, s.period_darts))
                    AS v (i, problem, count, darts)
         WHERE v.count > 0
         ORDER BY v.i;
END
$$;

COMMENT ON FUNCTION tgsis.gmap_check(bigint) IS
    'problems of a stored G-map (model 4) with the first offending darts: missing or dangling alpha rows, (i) non-involutions, (ii) fixed points below alpha_n, (iii) alpha_i o alpha_j not involutions (i + 2 <= j), darts sent into another topology period, 0-cells with several nodes, darts of missing nodes or periods; no rows: valid (the darts'' periods and nodes read from their chunk arrays when stored in chunks the caller may read)';
