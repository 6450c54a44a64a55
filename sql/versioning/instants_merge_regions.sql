-- tgsis.instants_merge_regions(version, geoid): the regions of the merge of one model-2 or model-3 feature, slice by slice, in SQL.
-- What the Python find_conflicts stores for such an object (tgsis._merge_slices.merge_sliced over
-- tgsis.merge3), so that SQL tgsis.find_conflicts stores it too (tgsis.store_mesh_regions) and a
-- psql merge that stops at an unsolved region of a slice names it. A slice is an instant of a surface
-- at instants (model 2) or a geometry instant (timem, timet) of a topology period of an evolving
-- surface (model 3). The slices are classified as the model's psql merge classifies them (its
-- registry row's merge_function, tgsis.data_models: tgsis.merge_instants_by_slice or
-- tgsis.merge_periods_by_slice; its analysis alone, p_action 'regions': nothing written, its slices in
-- pg_temp.tgsis_ms_slice or tgsis_mp_slice); the slices the three states have and a side changed are
-- merged by merge3, each through tgsis.mesh_merge_regions(version, geoid, times[, timem])
-- (tgsis.mesh_merge_work on that slice's rows); their regions are numbered on through the object's
-- slices in ascending order, as merge_sliced numbers them, each with its slice (times: the instant or
-- geometry instant; timem: the period, NULL for model 2). Refused (TG100, nothing found) for an
-- object-level conflict (an instant, period or geometry instant removed on one side and changed on the
-- other, added on both sides differently, a period's topology changed on both sides differently, a
-- per-instant property changed on both sides, deleted on one side, attributes changed on both sides)
-- and for a model-3 object no choice of solutions merges (its slices no solution changes would give a
-- period two topologies: tgsis._merge_slices.fixed_period_refusal, TG308 in the merge): the Python
-- find_conflicts finds no regions there either. 42501 for a role that may not read the class, TG302
-- for vertices with non-finite coordinates (merge3 takes no such state). extra_float_digits is pinned:
-- floats exact through jsonb; client_min_messages too.
CREATE FUNCTION tgsis.instants_merge_regions(p_version text, p_geoid bigint)
RETURNS TABLE (region integer, times double precision, timem double precision, conflict boolean, changed_by text,
               vertex_ids bigint[], cell_ids bigint[], parent_vertex_ids bigint[], parent_cell_ids bigint[],
               child_vertex_ids bigint[], child_cell_ids bigint[], bbox double precision[],
               parent_displacement double precision, child_displacement double precision, discards jsonb)
LANGUAGE plpgsql
VOLATILE
SET search_path = pg_catalog, pg_temp
SET extra_float_digits = 1
SET client_min_messages = warning
AS $$
#variable_conflict use_column
DECLARE
    v_function text;
    v_timemodel text;
    v_m     float8;
    v_t     float8;
    v_n     integer := 0;
    v_count integer;
    v_done  bigint;
BEGIN
    SELECT m.merge_function, m.timemodel INTO v_function, v_timemodel
      FROM tgsis.catalog c JOIN tgsis.data_models m ON m.timemodel = c.timemodel
     WHERE c.classname = tgsis.class_of_geoid(p_geoid);
    IF v_function IS NULL OR v_timemodel NOT IN ('INSTANTS', 'EVOLVING') THEN
        RAISE EXCEPTION 'feature % does not merge slice by slice: it is not a surface at instants nor an evolving surface', p_geoid
            USING ERRCODE = 'TG100', HINT = format('SELECT * FROM tgsis.mesh_merge_regions(%L, %s) finds the regions of a mesh', p_version, p_geoid);
    END IF;
    EXECUTE format('SELECT tgsis.%I($1, ''regions'', $2)', v_function) INTO v_done USING p_version, p_geoid;
    IF v_done IS NULL THEN
        RAISE EXCEPTION 'feature % does not merge slice by slice in version %: an object-level conflict', p_geoid, quote_literal(p_version)
            USING ERRCODE = 'TG100',
                  DETAIL = 'An instant (a period, a geometry instant) removed on one side and changed on the other, added on both sides differently, a period''s topology changed on both sides differently or made two by the slices no solution changes, a per-instant property changed on both sides, the feature deleted on one side or its attributes changed on both.',
                  HINT = format('solve it as a whole object: SELECT tgsis.resolve_conflict(%L, ''feature'', %L, ''parent''|''child''|''manual'')',
                                p_version, p_geoid::text);
    END IF;
    -- the slices the three states have and a side changed, as merge_sliced merges them by merge3
    FOR v_m, v_t IN EXECUTE
        CASE v_timemodel WHEN 'INSTANTS' THEN 'SELECT NULL::float8, s.t FROM pg_temp.tgsis_ms_slice s' ELSE 'SELECT s.m, s.t FROM pg_temp.tgsis_mp_slice s' END
        || ' WHERE s.ib AND s.ip AND s.ic AND (s.chp OR s.chc) ORDER BY 1, 2'
    LOOP
        RETURN QUERY
        SELECT r.region + v_n, v_t, v_m, r.conflict, r.changed_by, r.vertex_ids, r.cell_ids, r.parent_vertex_ids,
               r.parent_cell_ids, r.child_vertex_ids, r.child_cell_ids, r.bbox, r.parent_displacement,
               r.child_displacement, r.discards
          FROM tgsis.mesh_merge_regions(p_version, p_geoid, v_t, v_m) AS r
         ORDER BY r.region;
        GET DIAGNOSTICS v_count = ROW_COUNT;
        v_n := v_n + v_count;
    END LOOP;
END
$$;

COMMENT ON FUNCTION tgsis.instants_merge_regions(text, bigint) IS
    'the regions of the merge of a model-2 or model-3 feature changed both in a version and in its parent, slice by slice (an instant; a geometry instant of a topology period), computed in SQL as the Python find_conflicts finds them (merge3 per slice the three states have and a side changed), numbered on through the slices, each with its slice (times, timem); TG100 for an object-level conflict or a model-3 object no solution merges (TG308), 42501 for a class the role may not read';

-- internal to the merges, not executable by PUBLIC (tests/test_function_grants.py); tgsis.store_mesh_regions runs it
REVOKE ALL ON FUNCTION tgsis.instants_merge_regions(text, bigint) FROM PUBLIC;
