-- tgsis.merge_instant_by_region(version, geoid, instant, refused, hint): the merged rows of one instant of a model-2 feature both sides changed, by region, in SQL.
-- For tgsis.merge_instants_by_slice: an instant the three states have is merged by merge3 in the
-- Python merge (tgsis._merge_slices.merge_sliced, apply_sliced); here its regions are
-- tgsis.mesh_merge_work's on that instant's rows (the same as merge3's), and the merged state is,
-- per region, the rows of the side that changed it (a region both changed alike: the parent's), a
-- conflicting one the rows of the solution tgsis.resolve_region recorded for it (parent, child, base;
-- the stored region of the object numbered on through its instants, times = the instant), the
-- parent's elsewhere, the version's new ids as merge3 renumbers them. Returns, without writing
-- anything, {"rows": [[kind, merged id, source state, id in that state, the cell's vertex ids in the
-- merged numbering or null], ...], "notes": [what each solution discards, as merge3's RegionDiscard]}
-- over the keys the states do not all hold alike (a row the source state lacks is left out: removed);
-- the caller writes them by its (instant, id)-keyed difference. NULL when a conflicting region has no
-- solution (or no regions are stored): the object stays unsolved. Refused (TG302, with p_refused and
-- p_hint) when the stored regions of the instant are not its regions of now, or a region is solved
-- average or manual (the Python client applies those); TG302 too (the engine's reason and hint) when the
-- instant does not merge by region (tgsis.mesh_merge_work's TG100: the version's new ids cannot be
-- renumbered within bigint), as the Python merge refuses it. The work tables are made in a subtransaction
-- rolled back before it returns: neither they nor their locks outlive the call.
-- extra_float_digits is pinned: floats go through jsonb as their exact text.
CREATE FUNCTION tgsis.merge_instant_by_region(p_version text, p_geoid bigint, p_times float8, p_refused text, p_hint text)
RETURNS jsonb
LANGUAGE plpgsql
VOLATILE
SET search_path = pg_catalog, pg_temp
SET extra_float_digits = 1
AS $$
DECLARE
    v_id       integer := tgsis.version_id(p_version);
    v_key      text := p_geoid::text;
    v_first    integer;
    v_out      jsonb;
    v_why      text;
    v_hint     text;
    v_unsolved boolean := false;
BEGIN
    v_first := (SELECT min(r.region) FROM tgsis.conflict_regions r
                 WHERE r.versionid = v_id AND r.objectclass = 'feature' AND r.objectkey = v_key AND r.times = p_times);
    -- the work, in a subtransaction rolled back once the plan is in v_out. The block's body is not indented.
    BEGIN
    BEGIN
        PERFORM tgsis.mesh_merge_work(p_version, p_geoid, p_times);
    EXCEPTION WHEN SQLSTATE 'TG100' THEN
        -- the instant does not merge by region (the version's new ids cannot be renumbered within bigint): the
        -- Python merge leaves the object unsolved and the merge refuses it (TG302), saying why
        GET STACKED DIAGNOSTICS v_why = MESSAGE_TEXT, v_hint = PG_EXCEPTION_HINT;
        RAISE EXCEPTION '%: %', p_refused, v_why USING ERRCODE = 'TG302', HINT = v_hint;
    END;
    -- the regions of the instant, numbered as tgsis.mesh_merge_regions numbers them, with what each side changed
    CREATE TEMPORARY TABLE tgsis_mi_node ON COMMIT DROP AS
    SELECT n.kind, n.id, (dense_rank() OVER (ORDER BY n.label) - 1)::integer AS region,
           coalesce(vx.p_changed, cx.p_changed, false) AS p_changed,
           coalesce(vx.c_changed, cx.c_changed, false) AS c_changed,
           coalesce(vx.differ, cx.differ, false) AS differ,
           CASE WHEN vx.ip AND vx.ic THEN sqrt((vx.cx - vx.px) * (vx.cx - vx.px) + (vx.cy - vx.py) * (vx.cy - vx.py)
                                               + (vx.cz - vx.pz) * (vx.cz - vx.pz)) END AS pc_dist,
           CASE WHEN vx.p_moved THEN sqrt((vx.px - vx.bx) * (vx.px - vx.bx) + (vx.py - vx.by) * (vx.py - vx.by)
                                          + (vx.pz - vx.bz) * (vx.pz - vx.bz)) END AS p_disp,
           CASE WHEN vx.c_moved THEN sqrt((vx.cx - vx.bx) * (vx.cx - vx.bx) + (vx.cy - vx.by) * (vx.cy - vx.by)
                                          + (vx.cz - vx.bz) * (vx.cz - vx.bz)) END AS c_disp
      FROM pg_temp.tgsis_mr_node n
      LEFT JOIN pg_temp.tgsis_mr_vx vx ON n.kind = 'v' AND vx.id = n.id
      LEFT JOIN pg_temp.tgsis_mr_cx cx ON n.kind = 'c' AND cx.id = n.id;
    CREATE TEMPORARY TABLE tgsis_mi_region ON COMMIT DROP AS
    SELECT f.*, v_first + f.region AS number, r.solution,
           coalesce(r.vertex_ids = f.vertex_ids AND r.cell_ids = f.cell_ids AND r.parent_vertex_ids = f.pv
                    AND r.parent_cell_ids = f.pc AND r.child_vertex_ids = f.cv AND r.child_cell_ids = f.cc
                    AND r.conflict = f.conflict, false) AS holds,
           CASE WHEN NOT f.conflict THEN CASE WHEN f.has_c AND NOT f.has_p THEN 4 ELSE 2 END
                WHEN r.solution = 'parent' THEN 2 WHEN r.solution = 'child' THEN 4 WHEN r.solution = 'base' THEN 1
           END::smallint AS src
      FROM (SELECT d.region, bool_or(d.p_changed) AND bool_or(d.c_changed) AND bool_or(d.differ) AS conflict,
                   bool_or(d.p_changed) AS has_p, bool_or(d.c_changed) AS has_c,
                   coalesce(array_agg(d.id ORDER BY d.id) FILTER (WHERE d.kind = 'v'), '{}') AS vertex_ids,
                   coalesce(array_agg(d.id ORDER BY d.id) FILTER (WHERE d.kind = 'c'), '{}') AS cell_ids,
                   coalesce(array_agg(d.id ORDER BY d.id) FILTER (WHERE d.kind = 'v' AND d.p_changed), '{}') AS pv,
                   coalesce(array_agg(d.id ORDER BY d.id) FILTER (WHERE d.kind = 'c' AND d.p_changed), '{}') AS pc,
                   coalesce(array_agg(d.id ORDER BY d.id) FILTER (WHERE d.kind = 'v' AND d.c_changed), '{}') AS cv,
                   coalesce(array_agg(d.id ORDER BY d.id) FILTER (WHERE d.kind = 'c' AND d.c_changed), '{}') AS cc,
                   -- what a whole-region solution discards of each side (merge3's RegionDiscard)
                   count(*) FILTER (WHERE d.kind = 'v' AND d.c_changed AND d.differ) AS pcv,
                   count(*) FILTER (WHERE d.kind = 'c' AND d.c_changed AND d.differ) AS pcc,
                   coalesce(max(d.pc_dist) FILTER (WHERE d.kind = 'v' AND d.c_changed AND d.differ), 0) AS pcd,
                   count(*) FILTER (WHERE d.kind = 'v' AND d.p_changed AND d.differ) AS cpv,
                   count(*) FILTER (WHERE d.kind = 'c' AND d.p_changed AND d.differ) AS cpc,
                   coalesce(max(d.pc_dist) FILTER (WHERE d.kind = 'v' AND d.p_changed AND d.differ), 0) AS cpd,
                   count(*) FILTER (WHERE d.kind = 'v' AND d.p_changed) AS bpv,
                   count(*) FILTER (WHERE d.kind = 'c' AND d.p_changed) AS bpc,
                   coalesce(max(d.p_disp), 0) AS bpd,
                   count(*) FILTER (WHERE d.kind = 'v' AND d.c_changed) AS bcv,
                   count(*) FILTER (WHERE d.kind = 'c' AND d.c_changed) AS bcc,
                   coalesce(max(d.c_disp), 0) AS bcd
              FROM pg_temp.tgsis_mi_node d GROUP BY d.region) AS f
      LEFT JOIN tgsis.conflict_regions r
        ON r.versionid = v_id AND r.objectclass = 'feature' AND r.objectkey = v_key AND r.times = p_times
       AND r.region = v_first + f.region;

    IF EXISTS (SELECT FROM pg_temp.tgsis_mi_region g WHERE g.conflict) THEN
        IF v_first IS NULL THEN  -- no regions stored (none could be solved): unsolved
            v_unsolved := true;
            RAISE EXCEPTION 'tgsis_mi_done';
        END IF;
        -- the recorded solutions hold only for these very regions (else every conflict is unsolved, as in Python)
        IF EXISTS (SELECT FROM pg_temp.tgsis_mi_region g WHERE NOT g.holds)
           OR (SELECT count(*) FROM tgsis.conflict_regions r WHERE r.versionid = v_id AND r.objectclass = 'feature'
                  AND r.objectkey = v_key AND r.times = p_times) <> (SELECT count(*) FROM pg_temp.tgsis_mi_region) THEN
            RAISE EXCEPTION '%: its stored regions at instant % are not the regions of its states now: their solutions do not hold',
                    p_refused, p_times
                USING ERRCODE = 'TG302',
                      HINT = format('SELECT * FROM tgsis.find_conflicts(%L) finds them again; then solve them (tgsis.resolve_region)', p_version);
        END IF;
        SELECT string_agg(format('region %s at instant %s solved %s', g.number, p_times, g.solution), ', ' ORDER BY g.region)
          INTO v_why
          FROM pg_temp.tgsis_mi_region g WHERE g.conflict AND g.solution IN ('average', 'manual');
        IF v_why IS NOT NULL THEN
            RAISE EXCEPTION '%: % (the Python client applies it)', p_refused, v_why
                USING ERRCODE = 'TG302', HINT = p_hint;
        END IF;
        IF EXISTS (SELECT FROM pg_temp.tgsis_mi_region g WHERE g.conflict AND g.src IS NULL) THEN
            v_unsolved := true;  -- a conflicting region without a solution
            RAISE EXCEPTION 'tgsis_mi_done';
        END IF;
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
                                                   LEFT JOIN (SELECT n.id, g.src FROM pg_temp.tgsis_mi_node n
                                                                JOIN pg_temp.tgsis_mi_region g USING (region)
                                                               WHERE n.kind = 'v') AS s ON s.id = m.id) AS k
                                           LEFT JOIN pg_temp.tgsis_mr_vmap p ON p.new = k.id
                                          WHERE EXISTS (SELECT FROM pg_temp.tgsis_mr_v m WHERE m.id = k.id AND m.st = k.src)
                                         UNION ALL
                                         SELECT 'c', k.id, k.src, CASE WHEN k.src = 4 THEN coalesce(p.old, k.id) ELSE k.id END,
                                                CASE WHEN k.src = 4 THEN m.v END
                                           FROM (SELECT DISTINCT m.id, coalesce(s.src, 2::smallint) AS src
                                                   FROM pg_temp.tgsis_mr_c m
                                                   LEFT JOIN (SELECT n.id, g.src FROM pg_temp.tgsis_mi_node n
                                                                JOIN pg_temp.tgsis_mi_region g USING (region)
                                                               WHERE n.kind = 'c') AS s ON s.id = m.id) AS k
                                           JOIN pg_temp.tgsis_mr_c m ON m.id = k.id AND m.st = k.src
                                           LEFT JOIN pg_temp.tgsis_mr_cmap p ON p.new = k.id) AS q), '[]'),
               'notes', coalesce((SELECT jsonb_agg(format('region %s at instant %s: %s discards the %s''s edit there: %s vertices, %s cells, largest displacement %s',
                                                          n.number, p_times, n.solution, n.side, n.nv, n.nc, tgsis.merge_number_text(n.d))
                                                   ORDER BY n.number, n.o)
                                    FROM (SELECT g.number, g.solution, s.o, s.side, s.nv, s.nc, s.d
                                            FROM pg_temp.tgsis_mi_region g
                                           CROSS JOIN LATERAL (VALUES
                                               (1, 'parent', CASE g.solution WHEN 'child' THEN g.cpv WHEN 'base' THEN g.bpv END,
                                                             CASE g.solution WHEN 'child' THEN g.cpc WHEN 'base' THEN g.bpc END,
                                                             CASE g.solution WHEN 'child' THEN g.cpd WHEN 'base' THEN g.bpd END),
                                               (2, 'child', CASE g.solution WHEN 'parent' THEN g.pcv WHEN 'base' THEN g.bcv END,
                                                            CASE g.solution WHEN 'parent' THEN g.pcc WHEN 'base' THEN g.bcc END,
                                                            CASE g.solution WHEN 'parent' THEN g.pcd WHEN 'base' THEN g.bcd END))
                                                AS s (o, side, nv, nc, d)
                                          WHERE g.conflict AND (s.nv > 0 OR s.nc > 0)) AS n), '[]'))
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

COMMENT ON FUNCTION tgsis.merge_instant_by_region(text, bigint, float8, text, text) IS
    'the merged rows of one instant of a model-2 feature both sides changed, by region (tgsis.mesh_merge_work on that instant; the solutions recorded for its conflicting regions), as jsonb {rows, notes} for tgsis.merge_instants_by_slice to write; NULL when a conflicting region has no solution; TG302 for stale stored regions or an average or manual solution';

-- internal to the merges: reached only through the SECURITY DEFINER merge and refresh, as their owner; not
-- executable by PUBLIC (tests/test_function_grants.py)
REVOKE ALL ON FUNCTION tgsis.merge_instant_by_region(text, bigint, float8, text, text) FROM PUBLIC;
