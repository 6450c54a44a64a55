-- tgsis.record_conflict_regions(version, objectclass, objectkey, childmark, parentmark, regions):
-- store the regions the three-way merge found for one conflicting object.
-- The regions are computed by the client (tgsis.find_conflicts in Python runs
-- tgsis.merge3 on the three states it read in the snapshot it read the
-- marks in) and hold for those marks only: the call is refused (TG307) when
-- they are not the conflict's marks now, so regions of another state are
-- never stored. It replaces the object's regions; a region whose six id
-- arrays are those of a stored region of the same marks keeps its solution
-- (finding the regions again loses no work). Only a role that stores
-- conflicts (tgsis.find_conflicts: one that may write in the version or
-- merge into its parent) records them. p_regions is a JSON array with one
-- object per region, regions numbered 0, 1, ... in order:
--   {"region": 0, "conflict": true, "changed_by": "both",
--    "vertex_ids": [...], "cell_ids": [...], "parent_vertex_ids": [...], "parent_cell_ids": [...],
--    "child_vertex_ids": [...], "child_cell_ids": [...],
--    "bbox": [xmin, ymin, zmin, xmax, ymax, zmax] or null,
--    "parent_displacement": 0.0, "child_displacement": 1.5}
-- and, for a region of a temporal surface (model 2 or 3), the slice it lies in:
-- "times" (the instant, or the geometry instant) and, model 3, "timem" (the
-- topology period); absent or null for a model-1 mesh.
CREATE FUNCTION tgsis.record_conflict_regions(p_version text, p_objectclass text, p_objectkey text,
                                              p_childmark text, p_parentmark text, p_regions jsonb)
RETURNS integer
LANGUAGE plpgsql
VOLATILE
SECURITY DEFINER
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_version tgsis.versions;
    v_role    name := tgsis.calling_role();
    v_key     text;
    v_row     tgsis.conflicts;
    v_r       jsonb;
    v_name    text;
    v_i       integer;
    v_ids     constant text[] := ARRAY['vertex_ids', 'cell_ids', 'parent_vertex_ids', 'parent_cell_ids',
                                       'child_vertex_ids', 'child_cell_ids'];
    v_keys    constant text[] := ARRAY['region', 'conflict', 'changed_by', 'vertex_ids', 'cell_ids',
                                       'parent_vertex_ids', 'parent_cell_ids', 'child_vertex_ids', 'child_cell_ids',
                                       'bbox', 'parent_displacement', 'child_displacement'];
    v_slice   constant text[] := ARRAY['times', 'timem'];  -- optional: the slice of a temporal surface
    v_count   integer;
BEGIN
    SELECT * INTO v_version FROM tgsis.versions WHERE versionid = tgsis.version_id(p_version);
    IF v_version.parentid IS NULL THEN
        RAISE EXCEPTION 'version DEFAULT has no parent to conflict with' USING ERRCODE = 'TG100';
    END IF;
    IF NOT (tgsis.holds_version_privilege(v_version.versionid, 'write', v_role)
            OR tgsis.holds_version_privilege(v_version.parentid, 'merge', v_role)) THEN
        RAISE EXCEPTION 'role % may not record the conflict regions of version %', quote_ident(v_role),
                quote_literal(v_version.name)
            USING ERRCODE = 'TG002',
                  DETAIL = 'That needs the write right on the version or the merge right on its parent, as storing its conflicts does.',
                  HINT = format('the owner or a tgsis_admin can run SELECT tgsis.grant_version(%L, %L, %L)',
                                v_version.name, 'write', v_role);
    END IF;
    IF p_childmark IS NULL OR p_parentmark IS NULL THEN
        RAISE EXCEPTION 'the regions of object % of class % in version % need the marks they were found on, not NULL',
                quote_literal(p_objectkey), quote_literal(p_objectclass), quote_literal(v_version.name)
            USING ERRCODE = 'TG100', HINT = 'give the childmark and parentmark of the row of tgsis.find_conflicts';
    END IF;

    -- the shape of p_regions, element by element: an error names the element and the key
    IF jsonb_typeof(p_regions) IS DISTINCT FROM 'array' THEN
        RAISE EXCEPTION 'the regions of object % of class % in version % are not a JSON array: %',
                quote_literal(p_objectkey), quote_literal(p_objectclass), quote_literal(v_version.name),
                coalesce(left(p_regions::text, 80), 'NULL')
            USING ERRCODE = 'TG100', HINT = 'give a JSON array with one object per region (''[]'' for none)';
    END IF;
    FOR v_i IN 0 .. jsonb_array_length(p_regions) - 1 LOOP
        v_r := p_regions -> v_i;
        IF jsonb_typeof(v_r) <> 'object' THEN
            RAISE EXCEPTION 'region % of object % of class % in version % is not a JSON object: %', v_i,
                    quote_literal(p_objectkey), quote_literal(p_objectclass), quote_literal(v_version.name), left(v_r::text, 80)
                USING ERRCODE = 'TG100', HINT = format('each element of the array is an object with the keys %s', array_to_string(v_keys, ', '));
        END IF;
        SELECT string_agg(k, ', ' ORDER BY k) INTO v_name FROM jsonb_object_keys(v_r) AS k
         WHERE k <> ALL (v_keys || v_slice);
        IF v_name IS NULL THEN
            SELECT string_agg(k, ', ' ORDER BY o) INTO v_name FROM unnest(v_keys) WITH ORDINALITY AS u(k, o) WHERE NOT v_r ? k;
            IF v_name IS NOT NULL THEN
                v_name := 'lacks ' || v_name;
            END IF;
        ELSE
            v_name := 'has unknown keys ' || v_name;
        END IF;
        IF v_name IS NULL THEN
            v_name := CASE
                WHEN jsonb_typeof(v_r -> 'region') <> 'number' OR (v_r ->> 'region') <> v_i::text
                    THEN format('has "region": %s where %s is due (regions are numbered 0, 1, ... in order)', v_r -> 'region', v_i)
                WHEN jsonb_typeof(v_r -> 'conflict') <> 'boolean' THEN format('has "conflict": %s, not true or false', v_r -> 'conflict')
                WHEN jsonb_typeof(v_r -> 'changed_by') <> 'string' OR (v_r ->> 'changed_by') NOT IN ('parent', 'child', 'both')
                    THEN format('has "changed_by": %s, not "parent", "child" or "both"', v_r -> 'changed_by')
                WHEN (v_r ->> 'conflict')::boolean AND v_r ->> 'changed_by' <> 'both'
                    THEN format('is a conflict changed by %s only: a conflict is changed by both sides', v_r ->> 'changed_by')
                WHEN jsonb_typeof(v_r -> 'parent_displacement') <> 'number' OR (v_r ->> 'parent_displacement')::float8 < 0
                    THEN format('has "parent_displacement": %s, not a number >= 0', v_r -> 'parent_displacement')
                WHEN jsonb_typeof(v_r -> 'child_displacement') <> 'number' OR (v_r ->> 'child_displacement')::float8 < 0
                    THEN format('has "child_displacement": %s, not a number >= 0', v_r -> 'child_displacement')
                WHEN jsonb_typeof(v_r -> 'bbox') <> 'null'
                     AND (jsonb_typeof(v_r -> 'bbox') <> 'array' OR jsonb_array_length(v_r -> 'bbox') <> 6
                          OR EXISTS (SELECT FROM jsonb_array_elements(v_r -> 'bbox') e WHERE jsonb_typeof(e) <> 'number'))
                    THEN format('has "bbox": %s, not null or 6 numbers (xmin, ymin, zmin, xmax, ymax, zmax)', left((v_r -> 'bbox')::text, 80))
                WHEN jsonb_typeof(coalesce(v_r -> 'times', 'null')) NOT IN ('null', 'number')
                    THEN format('has "times": %s, not null or a number', left((v_r -> 'times')::text, 80))
                WHEN jsonb_typeof(coalesce(v_r -> 'timem', 'null')) NOT IN ('null', 'number')
                    THEN format('has "timem": %s, not null or a number', left((v_r -> 'timem')::text, 80))
                WHEN jsonb_typeof(coalesce(v_r -> 'timem', 'null')) = 'number' AND jsonb_typeof(coalesce(v_r -> 'times', 'null')) <> 'number'
                    THEN 'has "timem" without "times": a region of a topology period lies in one of its geometry instants'
            END;
        END IF;
        IF v_name IS NULL THEN
            SELECT format('has %s: %s, not an array of integer ids', quote_ident(k), left((v_r -> k)::text, 80)) INTO v_name
              FROM unnest(v_ids) WITH ORDINALITY AS u(k, o)
             WHERE jsonb_typeof(v_r -> k) <> 'array'
                OR EXISTS (SELECT FROM jsonb_array_elements(v_r -> k) e
                            WHERE CASE WHEN jsonb_typeof(e) = 'number' AND e::text ~ '^-?[0-9]{1,19}$'  -- any bigint id
                                       THEN e::text::numeric NOT BETWEEN -9223372036854775808 AND 9223372036854775807
                                       ELSE true END)
             ORDER BY o LIMIT 1;
        END IF;
        IF v_name IS NOT NULL THEN
            RAISE EXCEPTION 'region % of object % of class % in version % %', v_i, quote_literal(p_objectkey),
                    quote_literal(p_objectclass), quote_literal(v_version.name), v_name
                USING ERRCODE = 'TG100', HINT = format('each element of the array is an object with the keys %s', array_to_string(v_keys, ', '));
        END IF;
    END LOOP;

    -- the marks: those of the conflict now (find_conflicts stores them, and drops regions of older ones)
    PERFORM tgsis.find_conflicts(p_version);
    v_key := (tgsis.canonical_object_keys(p_objectclass, ARRAY[p_objectkey]))[1];
    SELECT * INTO v_row FROM tgsis.conflicts
     WHERE versionid = v_version.versionid AND objectclass = p_objectclass AND objectkey = v_key;
    IF NOT FOUND THEN
        RAISE EXCEPTION 'object % of class % is not in conflict in version %', quote_literal(p_objectkey),
                quote_literal(p_objectclass), quote_literal(v_version.name)
            USING ERRCODE = 'TG200', HINT = format('SELECT * FROM tgsis.find_conflicts(%L) lists the conflicts', v_version.name);
    END IF;
    IF (v_row.childmark, v_row.parentmark) IS DISTINCT FROM (p_childmark, p_parentmark) THEN
        RAISE EXCEPTION 'the regions of object % of class % in version % were found on a state that changed since',
                quote_literal(v_key), quote_literal(p_objectclass), quote_literal(v_version.name)
            USING ERRCODE = 'TG307',
                  DETAIL = format('They were found on the marks (%s, %s); the conflict''s are (%s, %s) now.',
                                  p_childmark, p_parentmark, v_row.childmark, v_row.parentmark),
                  HINT = 'find the regions again on the object''s current state (tgsis.find_conflicts in Python, or tgsis version conflicts)';
    END IF;

    INSERT INTO tgsis.conflict_regions AS o (versionid, objectclass, objectkey, region, childmark, parentmark, conflict,
                                             changed_by, vertex_ids, cell_ids, parent_vertex_ids, parent_cell_ids,
                                             child_vertex_ids, child_cell_ids, bbox, parent_displacement,
                                             child_displacement, solution, times, timem)
    SELECT v_version.versionid, p_objectclass, v_key, (e ->> 'region')::integer, p_childmark, p_parentmark,
           (e ->> 'conflict')::boolean, e ->> 'changed_by',
           ARRAY(SELECT x::bigint FROM jsonb_array_elements_text(e -> 'vertex_ids') WITH ORDINALITY AS a(x, o) ORDER BY o),
           ARRAY(SELECT x::bigint FROM jsonb_array_elements_text(e -> 'cell_ids') WITH ORDINALITY AS a(x, o) ORDER BY o),
           ARRAY(SELECT x::bigint FROM jsonb_array_elements_text(e -> 'parent_vertex_ids') WITH ORDINALITY AS a(x, o) ORDER BY o),
           ARRAY(SELECT x::bigint FROM jsonb_array_elements_text(e -> 'parent_cell_ids') WITH ORDINALITY AS a(x, o) ORDER BY o),
           ARRAY(SELECT x::bigint FROM jsonb_array_elements_text(e -> 'child_vertex_ids') WITH ORDINALITY AS a(x, o) ORDER BY o),
           ARRAY(SELECT x::bigint FROM jsonb_array_elements_text(e -> 'child_cell_ids') WITH ORDINALITY AS a(x, o) ORDER BY o),
           CASE WHEN jsonb_typeof(e -> 'bbox') = 'array'
                THEN ARRAY(SELECT x::float8 FROM jsonb_array_elements_text(e -> 'bbox') WITH ORDINALITY AS b(x, o) ORDER BY o) END,
           (e ->> 'parent_displacement')::float8, (e ->> 'child_displacement')::float8,
           CASE WHEN (e ->> 'conflict')::boolean THEN 'unsolved' ELSE 'automatic' END,
           (e ->> 'times')::float8, (e ->> 'timem')::float8
      FROM jsonb_array_elements(p_regions) AS e
        ON CONFLICT (versionid, objectclass, objectkey, region) DO UPDATE
       SET childmark = excluded.childmark, parentmark = excluded.parentmark, conflict = excluded.conflict,
           changed_by = excluded.changed_by, vertex_ids = excluded.vertex_ids, cell_ids = excluded.cell_ids,
           parent_vertex_ids = excluded.parent_vertex_ids, parent_cell_ids = excluded.parent_cell_ids,
           child_vertex_ids = excluded.child_vertex_ids, child_cell_ids = excluded.child_cell_ids, bbox = excluded.bbox,
           parent_displacement = excluded.parent_displacement, child_displacement = excluded.child_displacement,
           times = excluded.times, timem = excluded.timem,
           -- a solution holds for the region it was given on: the same marks, the same ids
           (solution, solution_mesh, solution_vertex_ids, solution_vertices, solution_cell_ids, solution_cells,
            solution_vertex_columns, solution_vertex_values, solution_cell_columns, solution_cell_values,
            solved_at, solved_by) = (
               SELECT CASE WHEN same THEN o.solution ELSE excluded.solution END,
                      CASE WHEN same THEN o.solution_mesh END,
                      CASE WHEN same THEN o.solution_vertex_ids END, CASE WHEN same THEN o.solution_vertices END,
                      CASE WHEN same THEN o.solution_cell_ids END, CASE WHEN same THEN o.solution_cells END,
                      CASE WHEN same THEN o.solution_vertex_columns END, CASE WHEN same THEN o.solution_vertex_values END,
                      CASE WHEN same THEN o.solution_cell_columns END, CASE WHEN same THEN o.solution_cell_values END,
                      CASE WHEN same THEN o.solved_at END,
                      CASE WHEN same THEN o.solved_by END
                 FROM (SELECT (o.childmark, o.parentmark) = (excluded.childmark, excluded.parentmark)
                              AND o.conflict AND excluded.conflict
                              AND o.vertex_ids = excluded.vertex_ids AND o.cell_ids = excluded.cell_ids
                              AND o.parent_vertex_ids = excluded.parent_vertex_ids
                              AND o.parent_cell_ids = excluded.parent_cell_ids
                              AND o.child_vertex_ids = excluded.child_vertex_ids
                              AND o.child_cell_ids = excluded.child_cell_ids
                              AND o.times IS NOT DISTINCT FROM excluded.times
                              AND o.timem IS NOT DISTINCT FROM excluded.timem AS same) AS s);
    GET DIAGNOSTICS v_count = ROW_COUNT;
    DELETE FROM tgsis.conflict_regions o
     WHERE o.versionid = v_version.versionid AND o.objectclass = p_objectclass AND o.objectkey = v_key
       AND o.region >= v_count;
    RETURN v_count;
END
$$;

COMMENT ON FUNCTION tgsis.record_conflict_regions(text, text, text, text, text, jsonb) IS
    'store the regions the three-way merge found for one conflicting object on the given marks (refused, TG307, when they are no longer the conflict''s); replaces the object''s regions, keeping the solution of a region found again alike; for roles that store conflicts';
