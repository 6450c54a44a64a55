-- tgsis.mesh_merge_regions(version, geoid): the regions of the three-way merge of one model-1 mesh, in SQL.
-- The regions tgsis.merge3.three_way_merge finds (docs/merge.md, "Regions"),
-- computed set-based from the storage, so that a psql user's
-- tgsis.find_conflicts records them without the Python client (issue 39,
-- items 2 and 4). The three states are the object at the version's
-- initrevision (base), in the parent's and in the version's working sets;
-- only the rows whose visibility differs between the three sets are read
-- (revision or lastrevs in the symmetric difference of the sets, as the
-- Python reader reads them), then, by key, every row of those keys seen by a
-- set: the vertices (tgsis.vrtx, GOCAD atoms as the vertex value refid, the
-- vertex properties), the cells (the class's simplex table, the cell
-- properties, parts kept in tgsis.part as the cell value part). Rows of other
-- keys are the same in the three states. Then, as merge3 does:
--   * the version's new ids are renumbered (merge3's child renumbering: a new
--     row with the content of a parent's new row takes its id, pairing the
--     k-th of equal contents with the k-th; a new id the parent uses for
--     something else takes a fresh one above every id, ascending);
--   * each side's edit against the base: vertices moved, added, removed, or a
--     value changed; cells added, removed, reconnected (an odd permutation is
--     a reconnection: tgsis.oriented_cell_key), or a value changed; values
--     compare as merge3 compares them (NaN equals NaN and a missing row,
--     -0.0 equals 0.0);
--   * each side's footprint: its changed vertices and cells, the base cells
--     on a vertex it moved, added or removed (found through the vertex BRIN
--     of the cell storage, by a few spans of those vertex ids), the
--     vertices of the cells it added, removed or reconnected;
--   * regions: connected components of the footprints' vertices and cells
--     (a cell and a vertex of its row, base's or the side's, both in one
--     side's footprint), by union-find over the few changed elements (one
--     pass over their edges in arrays; each component's root is its least
--     element), numbered as merge3 numbers them (by their first element:
--     vertices ascending, then cells ascending);
--   * per region: its ids, each side's changed ids, a box over its vertices
--     and its cells' corners in the three states, the largest displacement of
--     each side, whether it is a conflict (both sides changed it and their
--     rows differ), and what each whole-region solution discards of each side
--     (discards: {"parent": {"child": [vertices, cells, largest displacement]},
--     "child": {"parent": [...]}, "base": {"parent": [...], "child": [...]}},
--     merge3's RegionDiscard).
-- p_times: the regions of that instant of a model-2 feature (a surface at
-- instants) the three states have, merge3's regions of that slice, numbered
-- from 0 within it (tgsis.store_mesh_regions numbers them on through the
-- object's instants, as tgsis._merge_slices does). p_timem too: those of the geometry instant p_times of
-- the topology period starting at p_timem of a model-3 feature (an evolving surface).
-- The work is tgsis.mesh_merge_work's (its tables, in a subtransaction
-- rolled back at the end: neither they nor their locks outlive the call);
-- this is its summary. A role that may not read the
-- feature's class is refused (42501): regions computed without its rows
-- would be wrong. A feature not changed on both sides is refused (TG300),
-- one that does not merge by region (tgsis.region_merge_refusal: deleted on
-- one side, ...) too (TG100), as the Python reader refuses them; one with a
-- NaN or infinite coordinate among the rows read (of any state) is refused
-- by name (TG302, as tgsis.merge_mesh_by_region refuses its merge). extra_float_digits is pinned: values are
-- compared as text, floats exactly; client_min_messages too: dropping the
-- work tables of an earlier call says nothing.
CREATE FUNCTION tgsis.mesh_merge_regions(p_version text, p_geoid bigint, p_times float8 DEFAULT NULL,
                                         p_timem float8 DEFAULT NULL)
RETURNS TABLE (region integer, conflict boolean, changed_by text, vertex_ids bigint[], cell_ids bigint[],
               parent_vertex_ids bigint[], parent_cell_ids bigint[], child_vertex_ids bigint[], child_cell_ids bigint[],
               bbox double precision[], parent_displacement double precision, child_displacement double precision,
               discards jsonb)
LANGUAGE plpgsql
VOLATILE
SET search_path = pg_catalog, pg_temp
SET extra_float_digits = 1
SET client_min_messages = warning
AS $$
#variable_conflict use_column
DECLARE
    v_out     jsonb;
    v_why     text;
BEGIN
    -- the work, in a subtransaction rolled back once the regions are in v_out: neither the work tables nor
    -- the locks on them outlive the call (a relation created and dropped keeps its lock until the
    -- transaction ends: about 100 per call, and a find_conflicts over many meshes ran out of the shared
    -- lock table). The block's body is not indented.
    BEGIN
    IF tgsis.mesh_merge_work(p_version, p_geoid, p_times, p_timem) = 0 THEN  -- no region
        v_out := '[]';
        RAISE EXCEPTION 'tgsis_mr_done';
    END IF;
    -- a state with non-finite coordinates (NaN, infinity: a psql UPDATE stores them) among the rows read is no
    -- mesh merge3 takes, and tgsis.merge_mesh_by_region refuses its merge: refused here too (TG302, through the
    -- handler below), so that no region is stored for a merge that will be refused (PostgreSQL's float8 takes
    -- NaN as equal to NaN: the comparisons above would not see it)
    -- (the ids listed here, not by tgsis.merge_ids_text: this runs with the caller's rights)
    SELECT format('feature %s (%s): vertices %s have non-finite coordinates', p_geoid,
                  CASE s.st WHEN 1 THEN 'base' WHEN 2 THEN 'parent' ELSE 'child' END,
                  (SELECT string_agg(i.id::text, ', ' ORDER BY i.id) || CASE WHEN max(i.n) > 10 THEN ', ...' ELSE '' END
                     FROM (SELECT m.id, count(*) OVER () AS n
                             FROM (SELECT m.id, m.x, m.y, m.z FROM pg_temp.tgsis_mr_v m WHERE m.st = s.st
                                   UNION ALL SELECT b.id, b.x, b.y, b.z FROM pg_temp.tgsis_mr_vb b) AS m
                            WHERE 'NaN'::float8 IN (m.x, m.y, m.z) OR 'Infinity'::float8 IN (abs(m.x), abs(m.y), abs(m.z))
                            ORDER BY m.id LIMIT 10) AS i))
      INTO v_why
      FROM (VALUES (1::smallint), (2), (4)) AS s (st)
     WHERE EXISTS (SELECT FROM (SELECT m.x, m.y, m.z FROM pg_temp.tgsis_mr_v m WHERE m.st = s.st
                                UNION ALL SELECT b.x, b.y, b.z FROM pg_temp.tgsis_mr_vb b) AS m
                    WHERE 'NaN'::float8 IN (m.x, m.y, m.z) OR 'Infinity'::float8 IN (abs(m.x), abs(m.y), abs(m.z)))
     ORDER BY s.st LIMIT 1;
    IF v_why IS NOT NULL THEN
        RAISE EXCEPTION 'tgsis_mr_refused';
    END IF;
    -- 8. per region: its ids, each side's edit, box, largest displacements, conflict (tgsis_mr_vb: the
    -- base's coordinates of vertices no side changed, corners of the region's cells)
    SELECT coalesce(jsonb_agg(to_jsonb(q) ORDER BY q.region), '[]') INTO v_out FROM (
    WITH nodes AS (
        SELECT n.kind, n.id, (dense_rank() OVER (ORDER BY n.label) - 1)::integer AS region,
               coalesce(vx.p_changed, cx.p_changed, false) AS p_changed,
               coalesce(vx.c_changed, cx.c_changed, false) AS c_changed,
               coalesce(vx.differ, cx.differ, false) AS differ,
               CASE WHEN vx.p_moved THEN sqrt((vx.px - vx.bx) * (vx.px - vx.bx) + (vx.py - vx.by) * (vx.py - vx.by)
                                              + (vx.pz - vx.bz) * (vx.pz - vx.bz)) END AS p_disp,
               CASE WHEN vx.c_moved THEN sqrt((vx.cx - vx.bx) * (vx.cx - vx.bx) + (vx.cy - vx.by) * (vx.cy - vx.by)
                                              + (vx.cz - vx.bz) * (vx.cz - vx.bz)) END AS c_disp,
               CASE WHEN vx.ip AND vx.ic THEN sqrt((vx.cx - vx.px) * (vx.cx - vx.px) + (vx.cy - vx.py) * (vx.cy - vx.py)
                                                   + (vx.cz - vx.pz) * (vx.cz - vx.pz)) END AS pc_dist
          FROM pg_temp.tgsis_mr_node n
          LEFT JOIN pg_temp.tgsis_mr_vx vx ON n.kind = 'v' AND vx.id = n.id
          LEFT JOIN pg_temp.tgsis_mr_cx cx ON n.kind = 'c' AND cx.id = n.id),
    cellrows AS (  -- each region cell's row in each state that has it (an unchanged one: the base's, everywhere)
        SELECT d.region, c.st, c.v FROM nodes d JOIN pg_temp.tgsis_mr_c c ON c.id = d.id WHERE d.kind = 'c'
        UNION ALL
        SELECT d.region, s.st, g.v
          FROM nodes d JOIN pg_temp.tgsis_mr_margin g ON g.id = d.id, (VALUES (1::smallint), (2), (4)) AS s (st)
         WHERE d.kind = 'c' AND NOT EXISTS (SELECT FROM pg_temp.tgsis_mr_c c WHERE c.id = d.id)),
    points AS (
        SELECT d.region, m.x, m.y, m.z FROM nodes d JOIN pg_temp.tgsis_mr_v m ON m.id = d.id WHERE d.kind = 'v'
        UNION ALL
        SELECT d.region, b.x, b.y, b.z FROM nodes d JOIN pg_temp.tgsis_mr_vb b ON b.id = d.id WHERE d.kind = 'v'
        UNION ALL
        SELECT r.region, coalesce(m.x, b.x), coalesce(m.y, b.y), coalesce(m.z, b.z)
          FROM cellrows r CROSS JOIN LATERAL unnest(r.v) AS u(vid)
          LEFT JOIN pg_temp.tgsis_mr_v m ON m.id = u.vid AND m.st = r.st
          LEFT JOIN pg_temp.tgsis_mr_vb b ON b.id = u.vid),
    boxes AS (
        SELECT p.region, ARRAY[min(p.x), min(p.y), min(p.z), max(p.x), max(p.y), max(p.z)] AS bbox
          FROM points p GROUP BY p.region),
    facts AS (
        SELECT d.region,
               coalesce(array_agg(d.id ORDER BY d.id) FILTER (WHERE d.kind = 'v'), '{}') AS vertex_ids,
               coalesce(array_agg(d.id ORDER BY d.id) FILTER (WHERE d.kind = 'c'), '{}') AS cell_ids,
               coalesce(array_agg(d.id ORDER BY d.id) FILTER (WHERE d.kind = 'v' AND d.p_changed), '{}') AS pv,
               coalesce(array_agg(d.id ORDER BY d.id) FILTER (WHERE d.kind = 'c' AND d.p_changed), '{}') AS pc,
               coalesce(array_agg(d.id ORDER BY d.id) FILTER (WHERE d.kind = 'v' AND d.c_changed), '{}') AS cv,
               coalesce(array_agg(d.id ORDER BY d.id) FILTER (WHERE d.kind = 'c' AND d.c_changed), '{}') AS cc,
               bool_or(d.p_changed) AS has_p, bool_or(d.c_changed) AS has_c, bool_or(d.differ) AS differ,
               coalesce(max(d.p_disp), 0) AS p_disp, coalesce(max(d.c_disp), 0) AS c_disp,
               -- what each whole-region solution discards of each side (merge3's RegionDiscard): the side's
               -- changed rows the solution's rows do not hold as the side has them, and the largest distance
               -- between the side's place of such a vertex and the solution's
               jsonb_build_object(
                   'parent', jsonb_build_object('child', jsonb_build_array(
                       count(*) FILTER (WHERE d.kind = 'v' AND d.c_changed AND d.differ),
                       count(*) FILTER (WHERE d.kind = 'c' AND d.c_changed AND d.differ),
                       coalesce(max(d.pc_dist) FILTER (WHERE d.kind = 'v' AND d.c_changed AND d.differ), 0))),
                   'child', jsonb_build_object('parent', jsonb_build_array(
                       count(*) FILTER (WHERE d.kind = 'v' AND d.p_changed AND d.differ),
                       count(*) FILTER (WHERE d.kind = 'c' AND d.p_changed AND d.differ),
                       coalesce(max(d.pc_dist) FILTER (WHERE d.kind = 'v' AND d.p_changed AND d.differ), 0))),
                   'base', jsonb_build_object(
                       'parent', jsonb_build_array(count(*) FILTER (WHERE d.kind = 'v' AND d.p_changed),
                                                   count(*) FILTER (WHERE d.kind = 'c' AND d.p_changed),
                                                   coalesce(max(d.p_disp), 0)),
                       'child', jsonb_build_array(count(*) FILTER (WHERE d.kind = 'v' AND d.c_changed),
                                                  count(*) FILTER (WHERE d.kind = 'c' AND d.c_changed),
                                                  coalesce(max(d.c_disp), 0)))) AS discards
          FROM nodes d GROUP BY d.region)
    SELECT f.region, f.has_p AND f.has_c AND f.differ AS conflict,
           CASE WHEN f.has_p AND f.has_c THEN 'both' WHEN f.has_p THEN 'parent' ELSE 'child' END AS changed_by,
           f.vertex_ids, f.cell_ids, f.pv AS parent_vertex_ids, f.pc AS parent_cell_ids, f.cv AS child_vertex_ids,
           f.cc AS child_cell_ids, b.bbox, f.p_disp AS parent_displacement, f.c_disp AS child_displacement, f.discards
      FROM facts f LEFT JOIN boxes b ON b.region = f.region) AS q;
    RAISE EXCEPTION 'tgsis_mr_done';  -- rolls the work tables and their locks back
    EXCEPTION WHEN raise_exception THEN
        IF SQLERRM = 'tgsis_mr_refused' THEN  -- (raised after the work's rollback: its tables and locks gone)
            RAISE EXCEPTION 'the regions of feature % are not found: %', p_geoid, v_why
                USING ERRCODE = 'TG302',
                      HINT = 'correct the coordinates in the version or its parent, or solve it as a whole object (tgsis.resolve_conflict)';
        ELSIF SQLERRM <> 'tgsis_mr_done' THEN
            RAISE;
        END IF;
    END;
    -- floats went through jsonb as their exact text (extra_float_digits 1): the same values come back
    RETURN QUERY
    SELECT r.region, r.conflict, r.changed_by, r.vertex_ids, r.cell_ids, r.parent_vertex_ids, r.parent_cell_ids,
           r.child_vertex_ids, r.child_cell_ids, r.bbox, r.parent_displacement, r.child_displacement, r.discards
      FROM jsonb_to_recordset(v_out) AS r (region integer, conflict boolean, changed_by text, vertex_ids bigint[],
                                            cell_ids bigint[], parent_vertex_ids bigint[], parent_cell_ids bigint[],
                                            child_vertex_ids bigint[], child_cell_ids bigint[],
                                            bbox double precision[], parent_displacement double precision,
                                            child_displacement double precision, discards jsonb)
     ORDER BY r.region;
END
$$;

COMMENT ON FUNCTION tgsis.mesh_merge_regions(text, bigint, float8, float8) IS
    'the regions of the three-way merge of a model-1 feature changed both in a version and in its parent, computed in SQL exactly as tgsis.merge3 finds them (ids per side, box, largest displacements, conflict); with p_times, those of that instant of a model-2 feature, numbered from 0 in the instant (the object numbers them on through its instants); with p_timem too, those of that geometry instant of that period of a model-3 feature; TG300 / TG100 for a feature not changed on both sides / that does not merge by region, 42501 for a class the role may not read';
