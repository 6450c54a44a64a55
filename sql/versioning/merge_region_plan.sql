-- tgsis.merge_region_plan(versionid, version, geoid, key, times, refused, hint): the merged state of one mesh (or one instant of it) from the region engine's work tables; true when it stays unsolved.
-- The one plan both psql merges by region make (tgsis.merge_mesh_by_region for a model-1 mesh,
-- tgsis.merge_instant_by_region for an instant of a surface at instants, p_times, or for a geometry
-- instant p_times of the topology period p_timem of an evolving surface), after
-- tgsis.mesh_merge_work has filled pg_temp.tgsis_mr_*: written once so that the two merge what
-- the Python merge (merge3.apply_solutions) merges alike and a third (model 3) can call it too.
-- It makes, ON COMMIT DROP, in the caller's subtransaction:
--   tgsis_mw_node    the regions' elements, regions numbered in the object (the stored regions of the
--                    slice start at their least number: an instant's regions follow the earlier
--                    instants'), what each side changed, the distances merge3's discards count;
--   tgsis_mw_region  per region: its ids, each side's changed ids, whether it is a conflict, its stored
--                    solution and whether the stored region is this very one (merge3's _same_region:
--                    the six id arrays and the conflict flag), its source (1 base, 2 parent, 4 version,
--                    8 the rows recorded with an average or manual solution);
--   tgsis_mw_notes   what each whole-region solution discards of each side (merge3's RegionDiscard);
--   tgsis_mw_v/_c    the merged rows of the keys the states do not all hold alike: per id its region's
--                    source (a row the source lacks is no row), the parent's outside every region; the
--                    rows of average and manual solutions put in by tgsis.merge_solution_rows (which
--                    checks them: TG302 with p_refused and p_hint) with what they discard.
-- Returns true, nothing more made, when a conflicting region has no solution or no region of the slice
-- is stored (none could be solved): the object stays unsolved. TG302 (p_refused) when the stored
-- regions of the slice are not its regions of now, or a region is solved average or manual with its
-- .npz only. No subtransaction of its own; reads tgsis.conflict_regions as its caller's owner.
CREATE FUNCTION tgsis.merge_region_plan(p_versionid integer, p_version text, p_geoid bigint, p_key text,
                                        p_times float8, p_refused text, p_hint text, p_timem float8 DEFAULT NULL)
RETURNS boolean
LANGUAGE plpgsql
VOLATILE
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_first integer;
    v_at    text := CASE WHEN p_times IS NULL THEN ''
                         WHEN p_timem IS NULL THEN format(' at instant %s', p_times)
                         ELSE format(' at geometry instant %s of the period starting at %s', p_times, p_timem) END;
    v_why   text;
BEGIN
    v_first := (SELECT min(r.region) FROM tgsis.conflict_regions r
                 WHERE r.versionid = p_versionid AND r.objectclass = 'feature' AND r.objectkey = p_key
                   AND r.times IS NOT DISTINCT FROM p_times AND r.timem IS NOT DISTINCT FROM p_timem);
    -- the regions, numbered as tgsis.mesh_merge_regions numbers them (on from the slice's first stored one)
    CREATE TEMPORARY TABLE tgsis_mw_node ON COMMIT DROP AS
    SELECT n.kind, n.id, coalesce(v_first, 0) + (dense_rank() OVER (ORDER BY n.label) - 1)::integer AS region,
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
    CREATE TEMPORARY TABLE tgsis_mw_region ON COMMIT DROP AS
    SELECT f.*, r.solution, r.solution_vertex_ids IS NOT NULL AS has_rows,
           -- the stored region is this one (tgsis.db.regions._same_region: the six id arrays, the conflict flag)
           coalesce(r.vertex_ids = f.vertex_ids AND r.cell_ids = f.cell_ids AND r.parent_vertex_ids = f.pv
                    AND r.parent_cell_ids = f.pc AND r.child_vertex_ids = f.cv AND r.child_cell_ids = f.cc
                    AND r.conflict = f.conflict, false) AS holds,
           CASE WHEN NOT f.conflict THEN CASE WHEN f.has_c AND NOT f.has_p THEN 4 ELSE 2 END
                WHEN r.solution = 'parent' THEN 2 WHEN r.solution = 'child' THEN 4 WHEN r.solution = 'base' THEN 1
                -- average, manual: the rows recorded with the solution (tgsis.merge_solution_rows)
                WHEN r.solution IN ('average', 'manual') AND r.solution_vertex_ids IS NOT NULL THEN 8
           END::smallint AS src
      FROM (SELECT d.region, bool_or(d.p_changed) AND bool_or(d.c_changed) AND bool_or(d.differ) AS conflict,
                   bool_or(d.p_changed) AS has_p, bool_or(d.c_changed) AS has_c,
                   coalesce(array_agg(d.id ORDER BY d.id) FILTER (WHERE d.kind = 'v'), '{}') AS vertex_ids,
                   coalesce(array_agg(d.id ORDER BY d.id) FILTER (WHERE d.kind = 'c'), '{}') AS cell_ids,
                   coalesce(array_agg(d.id ORDER BY d.id) FILTER (WHERE d.kind = 'v' AND d.p_changed), '{}') AS pv,
                   coalesce(array_agg(d.id ORDER BY d.id) FILTER (WHERE d.kind = 'c' AND d.p_changed), '{}') AS pc,
                   coalesce(array_agg(d.id ORDER BY d.id) FILTER (WHERE d.kind = 'v' AND d.c_changed), '{}') AS cv,
                   coalesce(array_agg(d.id ORDER BY d.id) FILTER (WHERE d.kind = 'c' AND d.c_changed), '{}') AS cc,
                   -- what a whole-region solution discards of each side (merge3's RegionDiscard): the side's changed
                   -- rows the solution does not hold as the side has them, the largest distance of such a vertex
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
              FROM pg_temp.tgsis_mw_node d GROUP BY d.region) AS f
      LEFT JOIN tgsis.conflict_regions r
        ON r.versionid = p_versionid AND r.objectclass = 'feature' AND r.objectkey = p_key
       AND r.times IS NOT DISTINCT FROM p_times AND r.timem IS NOT DISTINCT FROM p_timem AND r.region = f.region;

    IF EXISTS (SELECT FROM pg_temp.tgsis_mw_region g WHERE g.conflict) THEN
        IF v_first IS NULL THEN  -- no region of the slice stored (none could be solved): unsolved
            RETURN true;
        END IF;
        -- the recorded solutions hold only for these very regions (else every conflict is unsolved, as in Python)
        IF EXISTS (SELECT FROM pg_temp.tgsis_mw_region g WHERE NOT g.holds)
           OR (SELECT count(*) FROM tgsis.conflict_regions r
                WHERE r.versionid = p_versionid AND r.objectclass = 'feature' AND r.objectkey = p_key
                  AND r.times IS NOT DISTINCT FROM p_times AND r.timem IS NOT DISTINCT FROM p_timem) <> (SELECT count(*) FROM pg_temp.tgsis_mw_region) THEN
            RAISE EXCEPTION '%: its stored regions% are not the regions of its states now: their solutions do not hold',
                    p_refused, v_at
                USING ERRCODE = 'TG302',
                      HINT = format('SELECT * FROM tgsis.find_conflicts(%L) finds them again; then solve them (tgsis.resolve_region)', p_version);
        END IF;
        SELECT string_agg(format('region %s%s solved %s', g.region, v_at, g.solution), ', ' ORDER BY g.region) INTO v_why
          FROM pg_temp.tgsis_mw_region g WHERE g.conflict AND g.solution IN ('average', 'manual') AND NOT g.has_rows;
        IF v_why IS NOT NULL THEN  -- (recorded with the .npz only: before its rows were recorded, or by psql)
            RAISE EXCEPTION '%: % with its mesh only (the Python client applies it)', p_refused, v_why
                USING ERRCODE = 'TG302', HINT = p_hint;
        END IF;
        IF EXISTS (SELECT FROM pg_temp.tgsis_mw_region g WHERE g.conflict AND g.src IS NULL) THEN
            RETURN true;  -- a conflicting region without a solution
        END IF;
    END IF;

    -- what the whole-region solutions discard, said before it is written (as the Python client says them)
    CREATE TEMPORARY TABLE tgsis_mw_notes ON COMMIT DROP AS
        SELECT g.region, s.o, g.solution, s.side, s.nv, s.nc, s.d
          FROM pg_temp.tgsis_mw_region g
          CROSS JOIN LATERAL (VALUES
              (1, 'parent', CASE g.solution WHEN 'child' THEN g.cpv WHEN 'base' THEN g.bpv END,
                            CASE g.solution WHEN 'child' THEN g.cpc WHEN 'base' THEN g.bpc END,
                            CASE g.solution WHEN 'child' THEN g.cpd WHEN 'base' THEN g.bpd END),
              (2, 'child', CASE g.solution WHEN 'parent' THEN g.pcv WHEN 'base' THEN g.bcv END,
                           CASE g.solution WHEN 'parent' THEN g.pcc WHEN 'base' THEN g.bcc END,
                           CASE g.solution WHEN 'parent' THEN g.pcd WHEN 'base' THEN g.bcd END)) AS s (o, side, nv, nc, d)
         WHERE g.conflict AND (s.nv > 0 OR s.nc > 0);

    -- the merged rows of the keys the states do not all hold alike (the others are the same everywhere):
    -- per id its region's source (a row the source lacks is no row), the parent's outside every region
    CREATE TEMPORARY TABLE tgsis_mw_v ON COMMIT DROP AS
    SELECT k.id, coalesce(s.src, 2::smallint) AS src, m.id IS NOT NULL AS present, m.x, m.y, m.z, m.val, m.ref
      FROM (SELECT DISTINCT m.id FROM pg_temp.tgsis_mr_v m) AS k
      LEFT JOIN (SELECT n.id, g.src FROM pg_temp.tgsis_mw_node n JOIN pg_temp.tgsis_mw_region g USING (region)
                  WHERE n.kind = 'v') AS s ON s.id = k.id
      LEFT JOIN pg_temp.tgsis_mr_v m ON m.id = k.id AND m.st = coalesce(s.src, 2::smallint);
    CREATE TEMPORARY TABLE tgsis_mw_c ON COMMIT DROP AS
    SELECT k.id, coalesce(s.src, 2::smallint) AS src, m.id IS NOT NULL AS present, m.v, m.val, m.part
      FROM (SELECT DISTINCT m.id FROM pg_temp.tgsis_mr_c m) AS k
      LEFT JOIN (SELECT n.id, g.src FROM pg_temp.tgsis_mw_node n JOIN pg_temp.tgsis_mw_region g USING (region)
                  WHERE n.kind = 'c') AS s ON s.id = k.id
      LEFT JOIN pg_temp.tgsis_mr_c m ON m.id = k.id AND m.st = coalesce(s.src, 2::smallint);
    -- the regions solved average or manual: their recorded rows (no row of theirs: removed), and the new ids they add
    IF EXISTS (SELECT FROM pg_temp.tgsis_mw_region g WHERE g.src = 8) THEN
        PERFORM tgsis.merge_solution_rows(p_geoid, p_versionid, p_refused, p_hint);
        UPDATE pg_temp.tgsis_mw_v n SET present = false, x = NULL, y = NULL, z = NULL, val = NULL, ref = NULL WHERE n.src = 8;
        UPDATE pg_temp.tgsis_mw_c n SET present = false, v = NULL, val = NULL, part = NULL WHERE n.src = 8;
        DELETE FROM pg_temp.tgsis_mw_v n USING pg_temp.tgsis_mw_sv s WHERE s.id = n.id;
        DELETE FROM pg_temp.tgsis_mw_c n USING pg_temp.tgsis_mw_sc s WHERE s.id = n.id;
        INSERT INTO pg_temp.tgsis_mw_v (id, src, present, x, y, z, val, ref)
        SELECT s.id, 8, NOT s.gone, s.x, s.y, s.z, s.val, s.ref FROM pg_temp.tgsis_mw_sv s;
        INSERT INTO pg_temp.tgsis_mw_c (id, src, present, v, val, part)
        SELECT s.id, 8, NOT s.gone, s.v, s.val, s.part FROM pg_temp.tgsis_mw_sc s;
        -- what they discard of each side (merge3's _discards): the side's changed rows the merged rows do not hold
        -- as the side does (coordinates bit for bit, values; a cell as an oriented cell), the largest distance
        INSERT INTO pg_temp.tgsis_mw_notes
        SELECT g.region, s.o, g.solution, s.side,
               (SELECT count(*) FROM pg_temp.tgsis_mw_node n
                  LEFT JOIN pg_temp.tgsis_mr_v a ON a.id = n.id AND a.st = s.st
                  LEFT JOIN pg_temp.tgsis_mw_v m ON m.id = n.id AND m.present
                 WHERE n.region = g.region AND n.kind = 'v' AND CASE s.o WHEN 1 THEN n.p_changed ELSE n.c_changed END
                   AND NOT coalesce(float8send(a.x) = float8send(m.x) AND float8send(a.y) = float8send(m.y)
                                    AND float8send(a.z) = float8send(m.z) AND a.val IS NOT DISTINCT FROM m.val
                                    AND a.ref IS NOT DISTINCT FROM m.ref, a.id IS NULL AND m.id IS NULL)),
               (SELECT count(*) FROM pg_temp.tgsis_mw_node n
                  LEFT JOIN pg_temp.tgsis_mr_c a ON a.id = n.id AND a.st = s.st
                  LEFT JOIN pg_temp.tgsis_mw_c m ON m.id = n.id AND m.present
                 WHERE n.region = g.region AND n.kind = 'c' AND CASE s.o WHEN 1 THEN n.p_changed ELSE n.c_changed END
                   AND NOT coalesce(tgsis.oriented_cell_key(a.v) = tgsis.oriented_cell_key(m.v)
                                    AND a.val IS NOT DISTINCT FROM m.val AND a.part IS NOT DISTINCT FROM m.part,
                                    a.id IS NULL AND m.id IS NULL)),
               coalesce((SELECT max(sqrt((a.x - m.x) * (a.x - m.x) + (a.y - m.y) * (a.y - m.y) + (a.z - m.z) * (a.z - m.z)))
                           FROM pg_temp.tgsis_mw_node n
                           JOIN pg_temp.tgsis_mr_v a ON a.id = n.id AND a.st = s.st
                           JOIN pg_temp.tgsis_mw_v m ON m.id = n.id AND m.present
                          WHERE n.region = g.region AND n.kind = 'v' AND CASE s.o WHEN 1 THEN n.p_changed ELSE n.c_changed END
                            AND NOT (float8send(a.x) = float8send(m.x) AND float8send(a.y) = float8send(m.y)
                                     AND float8send(a.z) = float8send(m.z) AND a.val IS NOT DISTINCT FROM m.val
                                     AND a.ref IS NOT DISTINCT FROM m.ref)), 0)
          FROM pg_temp.tgsis_mw_region g
         CROSS JOIN (VALUES (1, 'parent', 2::smallint), (2, 'child', 4::smallint)) AS s (o, side, st)
         WHERE g.conflict AND g.src = 8;
        DELETE FROM pg_temp.tgsis_mw_notes t WHERE t.nv = 0 AND t.nc = 0;
    END IF;
    RETURN false;
END
$$;

COMMENT ON FUNCTION tgsis.merge_region_plan(integer, text, bigint, text, float8, text, text, float8) IS
    'the merged state of one mesh (p_times NULL), one instant of a surface at instants or one geometry instant (p_times) of a period (p_timem) of an evolving surface from the region engine''s work tables (tgsis.mesh_merge_work): regions numbered in the object, their sources from the recorded solutions, the merged rows, what the solutions discard, in pg_temp.tgsis_mw_*; true when the object stays unsolved; TG302 for stale stored regions or an average or manual solution recorded with its .npz only';

-- internal to the merges: reached only through the SECURITY DEFINER merge and refresh, as their owner; not
-- executable by PUBLIC (tests/test_function_grants.py)
REVOKE ALL ON FUNCTION tgsis.merge_region_plan(integer, text, bigint, text, float8, text, text, float8) FROM PUBLIC;
