-- tgsis.merge_instant_by_region(version, geoid, instant, refused, hint): the merged rows of one instant of a model-2 feature both sides changed, by region, in SQL.
-- For tgsis.merge_instants_by_slice: an instant the three states have is merged by merge3 in the
-- Python merge (tgsis._merge_slices.merge_sliced, apply_sliced); here its regions are
-- tgsis.mesh_merge_work's on that instant's rows (the same as merge3's), and the merged state is,
-- per region, the rows of the side that changed it (a region both changed alike: the parent's), a
-- conflicting one the rows of the solution tgsis.resolve_region recorded for it (parent, child, base;
-- average, manual: the rows recorded with it, tgsis.merge_solution_rows;
-- the stored region of the object numbered on through its instants, times = the instant), the
-- parent's elsewhere, the version's new ids as merge3 renumbers them. Returns, without writing
-- anything, {"rows": [[kind, merged id, source state, id in that state, the cell's vertex ids in the
-- merged numbering or null], ...; an average or manual solution's: [kind, id, 8, id, geometry texts,
-- property texts]], "old": [the version's rows of ids no state changed that such a solution rewrites or
-- removes], "notes": [what each solution discards, as merge3's RegionDiscard]}
-- over the keys the states do not all hold alike (a row the source state lacks is left out: removed);
-- the caller writes them by its (instant, id)-keyed difference. NULL when a conflicting region has no
-- solution (or no regions are stored): the object stays unsolved. Refused (TG302, with p_refused and
-- p_hint) when the stored regions of the instant are not its regions of now, a region is solved
-- average or manual with its .npz only (the Python client applies those), its recorded rows are refused
-- by tgsis.merge_solution_rows, or the merged instant is not valid (tgsis.merge_mesh_validity); TG302
-- too (the engine's reason and hint) when the instant does not merge by region (tgsis.mesh_merge_work's
-- TG100: the version's new ids cannot be renumbered within bigint), as the Python merge refuses it. The
-- work tables are made in a subtransaction
-- rolled back before it returns: neither they nor their locks outlive the call.
-- p_timem (model 3, tgsis.merge_periods_by_slice): the same for the geometry instant p_times of the
-- topology period starting at p_timem (the engine on that slice, the stored regions with that times and
-- timem; an average or manual solution's rows keyed by the period's node and triangle ids, merge3's
-- validity check on the period's triangles, tgsis.d4dtrgl).
-- extra_float_digits is pinned: floats go through jsonb as their exact text.
CREATE FUNCTION tgsis.merge_instant_by_region(p_version text, p_geoid bigint, p_times float8, p_refused text, p_hint text,
                                              p_timem float8 DEFAULT NULL)
RETURNS jsonb
LANGUAGE plpgsql
VOLATILE
SET search_path = pg_catalog, pg_temp
SET extra_float_digits = 1
AS $$
DECLARE
    v_id       integer := tgsis.version_id(p_version);
    v_key      text := p_geoid::text;
    v_out      jsonb;
    v_why      text;
    v_hint     text;
    v_unsolved boolean := false;
    v_tt       text := CASE WHEN p_times::text ~ '^-?[0-9]+$' THEN p_times::text || '.0' ELSE p_times::text END;
    v_at       text := CASE WHEN p_timem IS NULL THEN format('instant %s', p_times)
                            ELSE format('geometry instant %s of the period starting at %s', p_times, p_timem) END;
BEGIN
    -- the work, in a subtransaction rolled back once the plan is in v_out. The block's body is not indented.
    BEGIN
    BEGIN
        PERFORM tgsis.mesh_merge_work(p_version, p_geoid, p_times, p_timem);
    EXCEPTION WHEN SQLSTATE 'TG100' THEN
        -- the instant does not merge by region (the version's new ids cannot be renumbered within bigint): the
        -- Python merge leaves the object unsolved and the merge refuses it (TG302), saying why
        GET STACKED DIAGNOSTICS v_why = MESSAGE_TEXT, v_hint = PG_EXCEPTION_HINT;
        RAISE EXCEPTION '%: %', p_refused, v_why USING ERRCODE = 'TG302', HINT = v_hint;
    END;
    -- the regions of the instant (numbered in the object), their sources, the merged rows and what the solutions
    -- discard, in the work tables tgsis.merge_mesh_by_region uses (pg_temp.tgsis_mw_*), which
    -- tgsis.merge_mesh_validity reads too
    IF tgsis.merge_region_plan(v_id, p_version, p_geoid, v_key, p_times, p_refused, p_hint, p_timem) THEN
        v_unsolved := true;
        RAISE EXCEPTION 'tgsis_mi_done';
    END IF;
    IF pg_catalog.to_regclass('pg_temp.tgsis_mw_sv') IS NULL THEN  -- (no such solution: none of their rows)
        CREATE TEMPORARY TABLE tgsis_mw_sv (id bigint, x float8, y float8, z float8, w text[], inside boolean,
                                            changed boolean, based boolean, gone boolean, b_x float8, b_y float8,
                                            b_z float8, val text, bval text) ON COMMIT DROP;
        CREATE TEMPORARY TABLE tgsis_mw_sc (id bigint, v bigint[], w text[], inside boolean, changed boolean,
                                            based boolean, gone boolean, bv bigint[], val text, bval text) ON COMMIT DROP;
    END IF;
    -- merge3's validity check of the merged instant, where a solution's rows can re-mesh it (the Python merge checks
    -- every slice it merges; regions taken each from one side, or parent/child/base solutions, cannot break it: a
    -- cell on a vertex the other side removed, or two new cells on the same vertices, join their regions)
    IF EXISTS (SELECT FROM pg_temp.tgsis_mw_region g WHERE g.src = 8) THEN
    PERFORM tgsis.merge_mesh_validity(
        format('feature %s of class %s, %s', p_geoid, (SELECT i.classname FROM pg_temp.tgsis_mr_info i),
               -- (as tgsis._merge_slices names the slice, its times as Python's repr of a float)
               CASE WHEN p_timem IS NULL THEN format('instant %s', v_tt)
                    ELSE format('geometry instant %s of the period starting at %s', v_tt,
                                CASE WHEN p_timem::text ~ '^-?[0-9]+$' THEN p_timem::text || '.0' ELSE p_timem::text END) END),
        3, 'triangle', CASE WHEN p_timem IS NULL THEN 'times_trgl' ELSE 'd4dtrgl' END, p_geoid, (SELECT i.base FROM pg_temp.tgsis_mr_info i), p_refused, p_hint);
    END IF;

    -- the merged rows of the keys the states do not all hold alike: per id its region's source (a row the source
    -- lacks is no row), the parent's outside every region; a version's row under its merged id (renumbered)
    SELECT jsonb_build_object(
               'rows', coalesce((SELECT jsonb_agg(jsonb_build_array(q.kind, q.id, q.src, q.orig, q.v) ORDER BY q.kind DESC, q.id)
                                   FROM (SELECT 'v' AS kind, k.id, k.src,
                                                CASE WHEN k.src = 4 THEN coalesce(p.old, k.id) ELSE k.id END AS orig,
                                                NULL::bigint[] AS v
                                           FROM (SELECT DISTINCT m.id, coalesce(s.src, 2::smallint) AS src
                                                   FROM pg_temp.tgsis_mr_v m
                                                   LEFT JOIN (SELECT n.id, g.src FROM pg_temp.tgsis_mw_node n
                                                                JOIN pg_temp.tgsis_mw_region g USING (region)
                                                               WHERE n.kind = 'v') AS s ON s.id = m.id) AS k
                                           LEFT JOIN pg_temp.tgsis_mr_vmap p ON p.new = k.id
                                          WHERE EXISTS (SELECT FROM pg_temp.tgsis_mr_v m WHERE m.id = k.id AND m.st = k.src)
                                         UNION ALL
                                         SELECT 'c', k.id, k.src, CASE WHEN k.src = 4 THEN coalesce(p.old, k.id) ELSE k.id END,
                                                CASE WHEN k.src = 4 THEN m.v END
                                           FROM (SELECT DISTINCT m.id, coalesce(s.src, 2::smallint) AS src
                                                   FROM pg_temp.tgsis_mr_c m
                                                   LEFT JOIN (SELECT n.id, g.src FROM pg_temp.tgsis_mw_node n
                                                                JOIN pg_temp.tgsis_mw_region g USING (region)
                                                               WHERE n.kind = 'c') AS s ON s.id = m.id) AS k
                                           JOIN pg_temp.tgsis_mr_c m ON m.id = k.id AND m.st = k.src
                                           LEFT JOIN pg_temp.tgsis_mr_cmap p ON p.new = k.id) AS q), '[]')
                        -- the rows of average and manual solutions: [kind, id, 8, id, geometry texts, property texts]
                        || coalesce((SELECT jsonb_agg(jsonb_build_array(q.kind, q.id, 8, q.id, q.g, q.w) ORDER BY q.kind DESC, q.id)
                                       FROM (SELECT 'v' AS kind, n.id, ARRAY[s.x::text, s.y::text, s.z::text] AS g, s.w
                                               FROM pg_temp.tgsis_mw_v n JOIN pg_temp.tgsis_mw_sv s ON s.id = n.id
                                              WHERE n.src = 8 AND n.present
                                             UNION ALL
                                             SELECT 'c', n.id, n.v::text[], s.w
                                               FROM pg_temp.tgsis_mw_c n JOIN pg_temp.tgsis_mw_sc s ON s.id = n.id
                                              WHERE n.src = 8 AND n.present) AS q), '[]'),
               -- the rows of the instant no state changed that a solution rewrites or removes (a margin row): the
               -- version's row is the base's, which tgsis.merge_instants_by_slice did not read: [kind, id, its
               -- geometry bits, its property bits when the solution's values are the base's (else null: rewritten)]
               'old', coalesce((SELECT jsonb_agg(jsonb_build_array(q.kind, q.id, q.g, q.p) ORDER BY q.kind DESC, q.id)
                                  FROM (SELECT 'v' AS kind, s.id, ARRAY[s.b_x::text, s.b_y::text, s.b_z::text]::text AS g,
                                               CASE WHEN s.val IS NOT DISTINCT FROM s.bval AND NOT s.gone
                                                    THEN ARRAY(SELECT coalesce(e, 'NaN') FROM unnest(s.w) WITH ORDINALITY AS u(e, o)
                                                                ORDER BY u.o)::text END AS p
                                          FROM pg_temp.tgsis_mw_sv s WHERE s.inside AND NOT s.changed AND s.based
                                        UNION ALL
                                        SELECT 'c', s.id, s.bv::text,
                                               CASE WHEN s.val IS NOT DISTINCT FROM s.bval AND NOT s.gone
                                                    THEN ARRAY(SELECT coalesce(e, 'NaN') FROM unnest(s.w) WITH ORDINALITY AS u(e, o)
                                                                ORDER BY u.o)::text END
                                          FROM pg_temp.tgsis_mw_sc s WHERE s.inside AND NOT s.changed AND s.based) AS q), '[]'),
               'notes', coalesce((SELECT jsonb_agg(format('region %s at %s: %s discards the %s''s edit there: %s vertices, %s cells, largest displacement %s',
                                                          n.region, v_at, n.solution, n.side, n.nv, n.nc, tgsis.merge_number_text(n.d))
                                                   ORDER BY n.region, n.o)
                                    FROM pg_temp.tgsis_mw_notes n), '[]'))
      INTO v_out;
    RAISE EXCEPTION 'tgsis_mi_done';  -- rolls the work tables and their locks back
    EXCEPTION WHEN raise_exception THEN
        IF SQLERRM <> 'tgsis_mi_done' THEN
            RAISE;
        END IF;
    END;
    IF v_unsolved THEN
        RETURN NULL;
    END IF;
    RETURN v_out;
END
$$;

COMMENT ON FUNCTION tgsis.merge_instant_by_region(text, bigint, float8, text, text, float8) IS
    'the merged rows of one instant of a model-2 feature (or, p_timem, one geometry instant of a period of a model-3 feature) both sides changed, by region (tgsis.mesh_merge_work on that instant; the solutions recorded for its conflicting regions), as jsonb {rows, notes} for tgsis.merge_instants_by_slice to write; NULL when a conflicting region has no solution; TG302 for stale stored regions, an average or manual solution recorded with its .npz only or whose rows are refused, an invalid merged instant';

-- internal to the merges: reached only through the SECURITY DEFINER merge and refresh, as their owner; not
-- executable by PUBLIC (tests/test_function_grants.py)
REVOKE ALL ON FUNCTION tgsis.merge_instant_by_region(text, bigint, float8, text, text, float8) FROM PUBLIC;
