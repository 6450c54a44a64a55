-- tgsis.check_period_continuity(geoid, tolerance, from): refuse a model-3 surface or model-4 G-map whose shape jumps at a topology instant.
-- The design: the pre-object (last shape of a period) and the post-object
-- (first shape of the next) share their geometry, so that a snapshot never
-- jumps. Every write path that adds a topology period calls this in its
-- transaction (Python's insert_feature and append_period; after plain SQL
-- INSERTs of periods, call it before COMMIT): it raises TG204 naming the
-- first period whose gap (tgsis.period_gaps) exceeds the tolerance
-- (tgsis.gap_tolerance: the argument, the setting tgsis.period_tolerance,
-- or 1e-6 of the geometry's extent). With p_from only topology instants at
-- or after it are checked (an appended period, leaving older ones alone).
CREATE FUNCTION tgsis.check_period_continuity(p_geoid bigint, p_tolerance double precision DEFAULT NULL,
                                              p_from double precision DEFAULT NULL)
RETURNS void
LANGUAGE plpgsql
STABLE
SET search_path FROM CURRENT
SET extra_float_digits = 1  -- its messages name instants and periods exactly, whatever the session's setting
AS $$
DECLARE
    v_gap record;
BEGIN
    SELECT g.* INTO v_gap
      FROM tgsis.period_gaps(p_geoid, p_tolerance) g
     WHERE (p_from IS NULL OR g.timem >= p_from) AND g.gap > g.tolerance
     ORDER BY g.timem
     LIMIT 1;
    IF FOUND THEN
        RAISE EXCEPTION 'the topology period from % of geometry % does not start where the period from % ends: the shapes are % apart (largest gap at %), more than the tolerance %',
                v_gap.timem, p_geoid, v_gap.previous, CASE WHEN v_gap.exact THEN '' ELSE 'at least ' END || v_gap.gap,
                v_gap.place, v_gap.tolerance
            USING ERRCODE = 'TG204',
                  DETAIL = format('At a topology instant the shape before and the shape after must be the same (pre- and post-object share their geometry); matched by %s.',
                                  CASE v_gap.matching WHEN 'node order' THEN 'node order'
                                       WHEN 'surface' THEN 'the distance of each node to the other shape''s triangles, both ways'
                                       ELSE 'the distance of each point to the other shape''s edges, both ways' END),
                  HINT = 'start the new period on the last shape of the one before, allow a larger gap with the tolerance argument or SET tgsis.period_tolerance TO a distance, or store a sudden change as a short linear transition (docs/time.md, Topology changes)';
    END IF;
END
$$;

COMMENT ON FUNCTION tgsis.check_period_continuity(bigint, double precision, double precision) IS
    'models 3 and 4: raise TG204 naming the first topology period (from p_from on, if given) whose first shape lies farther than the tolerance from the last shape of the period before (tgsis.period_gaps, tgsis.gap_tolerance)';
