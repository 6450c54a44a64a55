-- tgsis.instants_merge_regions(version, geoid): the regions of the merge of one model-2 feature (a surface at instants), instant by instant, in SQL.
-- What the Python find_conflicts stores for such an object (tgsis._merge_slices.merge_sliced over
-- tgsis.merge3), so that SQL tgsis.find_conflicts stores it too (tgsis.store_mesh_regions) and a
-- psql merge that stops at an unsolved region of an instant names it: the instants are classified
-- as tgsis.merge_instants_by_slice classifies them (its analysis alone, p_action 'regions': nothing
-- written); the instants the three states have and a side changed are merged by merge3, each
-- through tgsis.mesh_merge_regions(version, geoid, instant) (tgsis.mesh_merge_work on that instant's
-- rows); their regions are numbered on through the object's instants in ascending order, as
-- merge_sliced numbers them, each with its instant (times). Refused (TG100, nothing found) for an
-- object-level conflict (an instant removed on one side and changed on the other, added on both
-- sides differently, a per-instant property changed on both sides, deleted on one side, attributes
-- changed on both sides): the Python find_conflicts finds no regions there either. 42501 for a role
-- that may not read the class, TG302 for vertices with non-finite coordinates (merge3 takes no such
-- state). extra_float_digits is pinned: floats exact through jsonb; client_min_messages too.
CREATE FUNCTION tgsis.instants_merge_regions(p_version text, p_geoid bigint)
RETURNS TABLE (region integer, times double precision, conflict boolean, changed_by text, vertex_ids bigint[],
               cell_ids bigint[], parent_vertex_ids bigint[], parent_cell_ids bigint[], child_vertex_ids bigint[],
               child_cell_ids bigint[], bbox double precision[], parent_displacement double precision,
               child_displacement double precision, discards jsonb)
LANGUAGE plpgsql
VOLATILE
SET search_path = pg_catalog, pg_temp
SET extra_float_digits = 1
SET client_min_messages = warning
AS $$
#variable_conflict use_column
DECLARE
    v_times float8[];
    v_t     float8;
    v_n     integer := 0;
    v_count integer;
BEGIN
    IF tgsis.merge_instants_by_slice(p_version, 'regions', p_geoid) IS NULL THEN
        RAISE EXCEPTION 'feature % does not merge instant by instant in version %: an object-level conflict', p_geoid, quote_literal(p_version)
            USING ERRCODE = 'TG100',
                  DETAIL = 'An instant removed on one side and changed on the other, added on both sides differently, a per-instant property changed on both sides, the feature deleted on one side or its attributes changed on both.',
                  HINT = format('solve it as a whole object: SELECT tgsis.resolve_conflict(%L, ''feature'', %L, ''parent''|''child''|''manual'')',
                                p_version, p_geoid::text);
    END IF;
    v_times := ARRAY(SELECT s.t FROM pg_temp.tgsis_ms_slice s WHERE s.ib AND s.ip AND s.ic AND (s.chp OR s.chc) ORDER BY s.t);
    FOREACH v_t IN ARRAY v_times LOOP
        RETURN QUERY
        SELECT r.region + v_n, v_t, r.conflict, r.changed_by, r.vertex_ids, r.cell_ids, r.parent_vertex_ids,
               r.parent_cell_ids, r.child_vertex_ids, r.child_cell_ids, r.bbox, r.parent_displacement,
               r.child_displacement, r.discards
          FROM tgsis.mesh_merge_regions(p_version, p_geoid, v_t) AS r
         ORDER BY r.region;
        GET DIAGNOSTICS v_count = ROW_COUNT;
        v_n := v_n + v_count;
    END LOOP;
END
$$;

COMMENT ON FUNCTION tgsis.instants_merge_regions(text, bigint) IS
    'the regions of the merge of a model-2 feature changed both in a version and in its parent, instant by instant, computed in SQL as the Python find_conflicts finds them (merge3 per instant the three states have and a side changed), numbered on through the instants, each with its instant; TG100 for an object-level conflict, 42501 for a class the role may not read';

-- internal to the merges, not executable by PUBLIC (tests/test_function_grants.py); tgsis.store_mesh_regions runs it
REVOKE ALL ON FUNCTION tgsis.instants_merge_regions(text, bigint) FROM PUBLIC;
