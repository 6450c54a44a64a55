-- tgsis.period_gaps(geoid, tolerance): for every topology instant of a model-3 surface or model-4 G-map, how far the shape after it lies from the shape before it.
-- The design: at a topology instant the object is duplicated into a
-- pre-object (old topology, the last shape of the period before) and a
-- post-object (new topology, the first shape of the new period) that share
-- their geometry. "Share" is measured so (docs/time.md, "Topology changes"):
--   * when both have as many nodes, node i of one is node i of the other (in
--     the order of their ids, as the client numbers them): the gap is the
--     largest distance between corresponding nodes; if it is within the
--     tolerance, that is the answer ("node order");
--   * otherwise (different vertex sets, or nodes not in corresponding order)
--     the gap is two-sided: the largest distance of a node of the
--     post-object from the pre-object and of a node of the pre-object from
--     the post-object -- to its triangles for a surface ("surface",
--     tgsis.surface_side_gap), to its edges and points for a G-map
--     ("edges", tgsis.gmap_side_gap). A cut along new vertices on old
--     triangles or edges, a merge, a re-triangulation of the same vertices
--     all have gap 0; a move of the shape does not.
-- One row per topology instant after the first: the instant, the one
-- before, the gap, where it is largest (node, and for a G-map a dart on it,
-- of the period named), how it was matched, whether the gap is exact (false:
-- at least that much, see tgsis.surface_side_gap) and the tolerance used
-- (tgsis.gap_tolerance).
CREATE FUNCTION tgsis.period_gaps(p_geoid bigint, p_tolerance double precision DEFAULT NULL)
RETURNS TABLE (timem double precision, previous double precision, gap double precision, place text, matching text,
               exact boolean, tolerance double precision)
LANGUAGE plpgsql
STABLE
SET search_path FROM CURRENT
SET extra_float_digits = 1  -- its messages name instants and periods exactly, whatever the session's setting
AS $$
#variable_conflict use_column
DECLARE
    v_model  text;
    v_tol    double precision;
    v_pair   record;
    v_pre    double precision;
    v_npre   bigint;
    v_npost  bigint;
    v_order  record;
    v_side1  record;
    v_side2  record;
    v_m      integer;
BEGIN
    SELECT g.timemodel INTO v_model FROM tgsis.geometry g WHERE g.geoid = p_geoid;
    IF NOT FOUND THEN
        RAISE EXCEPTION 'geometry % does not exist', p_geoid
            USING ERRCODE = 'TG200', HINT = 'SELECT geoid FROM tgsis.geometry lists the stored geometries';
    END IF;
    IF v_model NOT IN ('EVOLVING', 'GMAP') THEN
        PERFORM tgsis.no_model_rule(v_model, 'tgsis.period_gaps', '{EVOLVING,GMAP}');
    END IF;
    v_tol := tgsis.gap_tolerance(p_geoid, p_tolerance);
    SELECT g.embedding INTO v_m FROM tgsis.gmap g WHERE v_model = 'GMAP' AND g.geoid = p_geoid;
    FOR v_pair IN
        SELECT p.timem AS post, p.prev AS pre
          FROM (SELECT m.timem, lag(m.timem) OVER (ORDER BY m.timem) AS prev
                  FROM (SELECT t.timem FROM tgsis.timem t WHERE v_model = 'EVOLVING' AND t.geoid = p_geoid
                        UNION ALL
                        SELECT t.timem FROM tgsis.gmap_timem t WHERE v_model = 'GMAP' AND t.geoid = p_geoid) m) p
         WHERE p.prev IS NOT NULL
         ORDER BY p.timem
    LOOP
        timem := v_pair.post;
        previous := v_pair.pre;
        tolerance := v_tol;
        exact := true;
        IF v_model = 'EVOLVING' THEN
            SELECT max(t.timet) INTO v_pre FROM tgsis.timet t WHERE t.geoid = p_geoid AND t.timem = v_pair.pre;
            SELECT count(*) FILTER (WHERE v.timem = v_pair.pre), count(*) FILTER (WHERE v.timem = v_pair.post)
              INTO v_npre, v_npost
              FROM tgsis.d4dvrtx v
             WHERE v.geoid = p_geoid AND ((v.timem = v_pair.pre AND v.timet = v_pre) OR (v.timem = v_pair.post AND v.timet = v_pair.post));
        ELSE
            SELECT max(t.timet) INTO v_pre FROM tgsis.gmap_timet t WHERE t.geoid = p_geoid AND t.timem = v_pair.pre;
            SELECT count(*) FILTER (WHERE v.timem = v_pair.pre), count(*) FILTER (WHERE v.timem = v_pair.post)
              INTO v_npre, v_npost
              FROM tgsis.gmap_vertex v
             WHERE v.geoid = p_geoid AND ((v.timem = v_pair.pre AND v.timet = v_pre) OR (v.timem = v_pair.post AND v.timet = v_pair.post));
        END IF;
        CONTINUE WHEN v_pre IS NULL OR v_npre = 0 OR v_npost = 0;  -- no shape on one side: tgsis.check_geometry reports it

        -- as many nodes: node i of one is node i of the other
        v_order := NULL;
        IF v_npre = v_npost THEN
            -- the two shapes as arrays in node order, zipped by unnest: one pass, no join to plan badly
            IF v_model = 'EVOLVING' THEN
                SELECT d.dist, d.nodeid INTO v_order
                  FROM (SELECT z.nodeid, sqrt((z.ax - z.bx) ^ 2 + (z.ay - z.by_) ^ 2 + (z.az - z.bz) ^ 2) AS dist
                          FROM (SELECT array_agg(v.x ORDER BY v.nodeid) AS x, array_agg(v.y ORDER BY v.nodeid) AS y,
                                       array_agg(v.z ORDER BY v.nodeid) AS z
                                  FROM tgsis.d4dvrtx v WHERE v.geoid = p_geoid AND v.timem = v_pair.pre AND v.timet = v_pre) a,
                               (SELECT array_agg(v.nodeid ORDER BY v.nodeid) AS id, array_agg(v.x ORDER BY v.nodeid) AS x,
                                       array_agg(v.y ORDER BY v.nodeid) AS y, array_agg(v.z ORDER BY v.nodeid) AS z
                                  FROM tgsis.d4dvrtx v WHERE v.geoid = p_geoid AND v.timem = v_pair.post AND v.timet = v_pair.post) b,
                               unnest(a.x, a.y, a.z, b.x, b.y, b.z, b.id) AS z(ax, ay, az, bx, by_, bz, nodeid)) d
                 ORDER BY d.dist DESC, d.nodeid
                 LIMIT 1;
            ELSE
                -- m coordinates per point: both flattened alike, zipped, summed per point
                SELECT d.dist, d.nodeid INTO v_order
                  FROM (SELECT b.id[(z.k - 1) / v_m + 1] AS nodeid, sqrt(sum((z.ac - z.bc) ^ 2)) AS dist
                          FROM (SELECT array_agg(v.coordinate ORDER BY v.nodeid) AS c
                                  FROM tgsis.gmap_vertex v
                                 WHERE v.geoid = p_geoid AND v.timem = v_pair.pre AND v.timet = v_pre
                                   AND cardinality(v.coordinate) = v_m) a,
                               (SELECT array_agg(v.nodeid ORDER BY v.nodeid) AS id, array_agg(v.coordinate ORDER BY v.nodeid) AS c
                                  FROM tgsis.gmap_vertex v
                                 WHERE v.geoid = p_geoid AND v.timem = v_pair.post AND v.timet = v_pair.post
                                   AND cardinality(v.coordinate) = v_m) b,
                               unnest(a.c, b.c) WITH ORDINALITY AS z(ac, bc, k)
                         GROUP BY 1) d
                 ORDER BY d.dist DESC, d.nodeid
                 LIMIT 1;
            END IF;
            IF v_order.dist <= v_tol THEN   -- (NaN, a non-finite position, is more than any tolerance)
                gap := v_order.dist;
                place := tgsis.period_gap_place(p_geoid, v_model, v_order.nodeid, v_pair.post);
                matching := 'node order';
                RETURN NEXT;
                CONTINUE;
            END IF;
        END IF;

        -- different vertex sets (or not in corresponding order): each side's nodes against the other side's shape
        IF v_model = 'EVOLVING' THEN
            SELECT * INTO v_side1 FROM tgsis.surface_side_gap(p_geoid, v_pair.post, v_pair.post, v_pair.pre, v_pre, v_tol);
            SELECT * INTO v_side2 FROM tgsis.surface_side_gap(p_geoid, v_pair.pre, v_pre, v_pair.post, v_pair.post, v_tol);
            matching := 'surface';
        ELSE
            SELECT * INTO v_side1 FROM tgsis.gmap_side_gap(p_geoid, v_pair.post, v_pair.post, v_pair.pre, v_pre, v_tol);
            SELECT * INTO v_side2 FROM tgsis.gmap_side_gap(p_geoid, v_pair.pre, v_pre, v_pair.post, v_pair.post, v_tol);
            matching := 'edges';
        END IF;
        CONTINUE WHEN v_side1.gap IS NULL AND v_side2.gap IS NULL;
        IF v_side2.gap IS NULL OR v_side1.gap >= v_side2.gap THEN
            gap := v_side1.gap;
            place := tgsis.period_gap_place(p_geoid, v_model, v_side1.nodeid, v_pair.post);
        ELSE
            gap := v_side2.gap;
            place := tgsis.period_gap_place(p_geoid, v_model, v_side2.nodeid, v_pair.pre);
        END IF;
        exact := coalesce(v_side1.exact, true) AND coalesce(v_side2.exact, true);
        RETURN NEXT;
    END LOOP;
END
$$;

COMMENT ON FUNCTION tgsis.period_gaps(bigint, double precision) IS
    'models 3 and 4: per topology instant after the first, the gap between the shape before it and the shape after it (node order when both have as many nodes and that matches within the tolerance, else two-sided distance to the other''s triangles or edges), where it is largest, how it was matched, whether it is exact, and the tolerance (tgsis.gap_tolerance)';
