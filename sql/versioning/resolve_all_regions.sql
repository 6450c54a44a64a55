-- tgsis.resolve_all_regions(version, objectclass, objectkey, solution): one solution for every conflicting region of a mesh, from psql.
-- The SQL face of tgsis.resolve_all_regions in Python (docs/merge.md,
-- "Solutions per object"): parent, child or base for every conflicting
-- region of the feature at once, or unsolved to take them all back; the
-- regions that merge by themselves stay automatic (the other side's edits
-- there are kept, unlike resolve_conflict's whole side). All or nothing, in
-- the caller's transaction: the regions are those of now (tgsis.find_conflicts
-- finds them again, in SQL, when either side changed the object: regions
-- seen before on other marks are stale, TG307), every region is checked,
-- then what the solution discards of each side is said (NOTICEs: the sums
-- per side, then each region, in the words of the Python client) before all
-- are recorded. average needs the average shape, which the Python client
-- computes and stores as a mesh: refused here (TG307) with the command that
-- does it; manual is one region's mesh (tgsis.resolve_region), refused
-- (TG100). The same rights as tgsis.resolve_region: write in the version.
-- Its find_conflicts (the marks of now) finds no other object's regions
-- (tgsis.region_detection = 'client' around it): it finds its own
-- (tgsis.store_mesh_regions), so that solving n conflicts one by one does
-- not try every other unsolved mesh n times.
CREATE FUNCTION tgsis.resolve_all_regions(p_version text, p_objectclass text, p_objectkey text, p_solution text)
RETURNS SETOF tgsis.conflict_regions
LANGUAGE plpgsql
VOLATILE
SECURITY DEFINER
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_detect text;
    v_id       integer := tgsis.version_id(p_version);
    v_solution text := lower(p_solution);
    v_key      text;
    v_name     text;
    v_marks    text[];
    v_now      text[];
    v_side     record;
    v_region   record;
BEGIN
    v_name := format('feature %s in version %s', coalesce(p_objectkey, 'NULL'), quote_literal(p_version));
    IF v_solution = 'manual' THEN
        RAISE EXCEPTION 'solution manual of all the regions of %: a manual mesh is one region''s rows', v_name
            USING ERRCODE = 'TG100',
                  HINT = 'give it per region: SELECT tgsis.resolve_region(version, class, key, region, ''manual'', mesh)';
    END IF;
    IF v_solution IS NULL OR v_solution NOT IN ('parent', 'child', 'base', 'average', 'unsolved') THEN
        RAISE EXCEPTION 'solution % of all the regions of % is not parent, child, base, average or unsolved',
                coalesce(quote_literal(p_solution), 'NULL'), v_name
            USING ERRCODE = 'TG100',
                  HINT = format('SELECT * FROM tgsis.resolve_all_regions(%L, %L, %L, ''parent''|''child''|''base''|''unsolved'')',
                                p_version, p_objectclass, p_objectkey);
    END IF;
    PERFORM tgsis.require_version_privilege(v_id, 'write', 'resolve conflicts of');
    IF v_solution = 'average' THEN
        RAISE EXCEPTION 'solution average of all the regions of % needs the average shape of each region, which SQL does not compute',
                v_name
            USING ERRCODE = 'TG307',
                  DETAIL = 'The Python client computes it (the midpoint of the two sides, or a manual mesh where they were meshed differently) and stores it as the region''s mesh.',
                  HINT = format('run `tgsis version resolve %s %s average --region all`, or tgsis.resolve_all_regions(conn, %s, %s, ''average'') in Python; parent, child and base are recorded from SQL',
                                tgsis.shell_quote(p_version), tgsis.shell_quote(p_objectkey), pg_catalog.to_json(p_version)::text,
                                p_objectkey);
    END IF;
    v_key := (tgsis.canonical_object_keys(p_objectclass, ARRAY[p_objectkey]))[1];
    SELECT ARRAY[r.childmark, r.parentmark] INTO v_marks FROM tgsis.conflict_regions r
     WHERE r.versionid = v_id AND r.objectclass = p_objectclass AND r.objectkey = v_key LIMIT 1;
    v_detect := current_setting('tgsis.region_detection', true);
    PERFORM set_config('tgsis.region_detection', 'client', true);  -- (not a function SET: only a superuser may
    -- create a function that sets a parameter tgsis does not define)
    PERFORM tgsis.find_conflicts(p_version);  -- the marks of now: stale regions go
    PERFORM set_config('tgsis.region_detection', coalesce(v_detect, ''), true);
    IF p_objectclass = 'feature' THEN  -- and this object's are found again in SQL
        PERFORM tgsis.store_mesh_regions(p_version, v_key);
    END IF;
    SELECT ARRAY[r.childmark, r.parentmark] INTO v_now FROM tgsis.conflict_regions r
     WHERE r.versionid = v_id AND r.objectclass = p_objectclass AND r.objectkey = v_key LIMIT 1;
    IF v_marks IS NOT NULL AND v_now IS DISTINCT FROM v_marks THEN
        RAISE EXCEPTION 'the regions of % were found on a state that changed since: the object changed in the version or its parent',
                v_name
            USING ERRCODE = 'TG307',
                  HINT = format('look at the regions again (SELECT region, conflict, changed_by FROM tgsis.conflict_regions WHERE versionid = tgsis.version_id(%L)), then solve them',
                                p_version);
    ELSIF v_now IS NULL THEN
        RAISE EXCEPTION 'no regions of % are stored: it does not merge by region, or is not in conflict', v_name
            USING ERRCODE = 'TG200',
                  HINT = format('SELECT * FROM tgsis.find_conflicts(%L) lists the conflicts; SELECT * FROM tgsis.mesh_merge_regions(%L, key) says why a feature does not merge by region; tgsis.resolve_conflict solves it as a whole object',
                                p_version, p_version);
    END IF;
    PERFORM FROM tgsis.conflict_regions r
      WHERE r.versionid = v_id AND r.objectclass = p_objectclass AND r.objectkey = v_key AND r.conflict
        FOR UPDATE;
    IF NOT FOUND THEN
        RAISE EXCEPTION '% has no conflicting region: it merges by itself', v_name
            USING ERRCODE = 'TG307',
                  HINT = format('SELECT tgsis.merge_version(%L) merges it; nothing needs a solution', p_version);
    END IF;

    IF v_solution <> 'unsolved' THEN
        -- what it discards, said before it is recorded: the regions computed again on these marks must be
        -- the stored ones (another client may have found other regions)
        IF pg_catalog.to_regclass('pg_temp.tgsis_rar_lost') IS NOT NULL THEN
            DROP TABLE pg_temp.tgsis_rar_lost;
        END IF;
        CREATE TEMPORARY TABLE tgsis_rar_lost ON COMMIT DROP AS
        SELECT r.region, s.side, (m.discards -> v_solution -> s.side ->> 0)::bigint AS vertices,
               (m.discards -> v_solution -> s.side ->> 1)::bigint AS cells,
               (m.discards -> v_solution -> s.side ->> 2)::float8 AS largest,
               (m.vertex_ids, m.cell_ids, m.parent_vertex_ids, m.parent_cell_ids, m.child_vertex_ids, m.child_cell_ids)
                   IS NOT DISTINCT FROM
               (r.vertex_ids, r.cell_ids, r.parent_vertex_ids, r.parent_cell_ids, r.child_vertex_ids, r.child_cell_ids)
                   AS same
          FROM tgsis.conflict_regions r
          LEFT JOIN tgsis.mesh_merge_regions(p_version, v_key::bigint) AS m ON m.region = r.region
          CROSS JOIN (VALUES ('parent'), ('child')) AS s (side)
         WHERE r.versionid = v_id AND r.objectclass = p_objectclass AND r.objectkey = v_key AND r.conflict;
        IF EXISTS (SELECT FROM pg_temp.tgsis_rar_lost l WHERE NOT l.same) THEN
            RAISE EXCEPTION 'the stored regions of % are not those of the object''s states now', v_name
                USING ERRCODE = 'TG307', HINT = 'find the regions again: tgsis.find_conflicts(conn, version) in Python, or tgsis version conflicts';
        END IF;
        FOR v_side IN
            SELECT l.side, sum(l.vertices) AS vertices, sum(l.cells) AS cells, max(l.largest) AS largest, count(*) AS regions
              FROM pg_temp.tgsis_rar_lost l WHERE l.vertices > 0 OR l.cells > 0
             GROUP BY l.side ORDER BY l.side DESC
        LOOP
            RAISE NOTICE '%: % discards the %''s edit of % vertices and % cells in % region(s) (largest displacement %)',
                v_name, v_solution, CASE v_side.side WHEN 'child' THEN 'version' ELSE 'parent' END, v_side.vertices,
                v_side.cells, v_side.regions, rtrim(rtrim(round(v_side.largest::numeric, 6)::text, '0'), '.');
        END LOOP;
        FOR v_region IN
            SELECT l.* FROM pg_temp.tgsis_rar_lost l WHERE l.vertices > 0 OR l.cells > 0 ORDER BY l.region, l.side
        LOOP
            RAISE NOTICE '%: region %: % discards the %''s edit of % vertices and % cells (largest displacement %)',
                v_name, v_region.region, v_solution, CASE v_region.side WHEN 'child' THEN 'version' ELSE 'parent' END,
                v_region.vertices, v_region.cells, rtrim(rtrim(round(v_region.largest::numeric, 6)::text, '0'), '.');
        END LOOP;
        DROP TABLE pg_temp.tgsis_rar_lost;
    END IF;
    RETURN QUERY
    WITH solved AS (
        UPDATE tgsis.conflict_regions r
           SET solution = v_solution, solution_mesh = NULL,
               (solution_vertex_ids, solution_vertices, solution_cell_ids, solution_cells, solution_vertex_columns,
                solution_vertex_values, solution_cell_columns, solution_cell_values)
                 = (SELECT NULL::bigint[], NULL::float8[], NULL::bigint[], NULL::bigint[], NULL::text[], NULL::float8[],
                           NULL::text[], NULL::float8[]),
               solved_at = CASE WHEN v_solution <> 'unsolved' THEN now() END,
               solved_by = CASE WHEN v_solution <> 'unsolved' THEN tgsis.calling_role() END
         WHERE r.versionid = v_id AND r.objectclass = p_objectclass AND r.objectkey = v_key AND r.conflict
        RETURNING r.*)
    SELECT * FROM solved ORDER BY solved.region;
END
$$;

COMMENT ON FUNCTION tgsis.resolve_all_regions(text, text, text, text) IS
    'record one solution (parent, child, base; unsolved takes them back) for every conflicting region of a mesh at once, all or nothing, saying first (NOTICE) what it discards of each side; average is refused from SQL (the Python client computes it); the regions that merge by themselves stay automatic';
