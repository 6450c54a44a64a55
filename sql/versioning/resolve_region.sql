-- tgsis.resolve_region(version, objectclass, objectkey, region, solution, mesh): record how one
-- conflicting region of a mesh is to be merged (docs/merge.md, "Solutions per region").
-- parent, child, base: that state's rows of the region; average, manual: the
-- rows of p_mesh (an .npz of a tgsis.merge3.MeshState; the Python client
-- computes the average shape and says what a solution discards before it
-- records it: tgsis.resolve_region in Python); unsolved takes a solution back.
-- With the mesh, the Python client gives its rows in a form SQL reads
-- (p_vertex_ids .. p_cell_values: ids, coordinates, cells' vertex ids, scalar
-- property values by column, NaN for none), kept in the solution_* columns:
-- the psql merge (tgsis.merge_mesh_by_region) applies them, and checks them
-- as the Python merge checks the .npz's rows; a solution without them (the
-- .npz only) is merged by the Python client only. The rows of a region of a
-- slice are kept too, keyed by the slice's ids: an instant of a surface at
-- instants (model 2) and a geometry instant of an evolving surface's period
-- (model 3: node ids, triangle ids), applied by tgsis.merge_instant_by_region.
-- Rows that are not the
-- .npz's mesh (tgsis.npz_rows_differ) or have a cell on one vertex twice are
-- refused (TG100): the two merges never apply two copies that differ.
-- The conflict's marks are recomputed first (tgsis.find_conflicts): a region
-- found on a state either side changed since is stale and refused (TG307),
-- as is a region that is no conflict (it merges by itself). The key is read
-- in the key column's type with the session's settings, as resolve_conflict
-- reads it. The same right as resolve_conflict: write in the version; a mesh
-- (average, manual) also the right to change the feature (tgsis.check_class_write),
-- as the merge that applies it writes its rows.
-- Its find_conflicts (the marks of now) finds no other object's regions
-- (tgsis.region_detection = 'client' around it): it finds its own
-- (tgsis.store_mesh_regions), so that solving n conflicts one by one does
-- not try every other unsolved mesh n times.
CREATE FUNCTION tgsis.resolve_region(p_version text, p_objectclass text, p_objectkey text, p_region integer,
                                     p_solution text, p_mesh bytea DEFAULT NULL,
                                     p_vertex_ids bigint[] DEFAULT NULL, p_vertices float8[] DEFAULT NULL,
                                     p_cell_ids bigint[] DEFAULT NULL, p_cells bigint[] DEFAULT NULL,
                                     p_vertex_columns text[] DEFAULT NULL, p_vertex_values float8[] DEFAULT NULL,
                                     p_cell_columns text[] DEFAULT NULL, p_cell_values float8[] DEFAULT NULL)
RETURNS tgsis.conflict_regions
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
    v_stored   boolean;
    v_marks    text[];
    v_row      tgsis.conflict_regions;
    v_object   text;
    v_object_bad text;
BEGIN
    IF v_solution IS NULL OR v_solution NOT IN ('parent', 'child', 'base', 'average', 'manual', 'unsolved') THEN
        RAISE EXCEPTION 'solution % of a region is not parent, child, base, average, manual or unsolved',
                coalesce(quote_literal(p_solution), 'NULL')
            USING ERRCODE = 'TG100',
                  HINT = CASE WHEN v_solution = 'automatic'
                              THEN 'automatic is no choice: find_conflicts records it for the regions that merge by themselves'
                              ELSE 'SELECT tgsis.resolve_region(version, class, key, region, ''parent''|''child''|''base'') or ''average''|''manual'' with a mesh' END;
    END IF;
    v_object := format('region %s of object %s of class %s in version %s', coalesce(p_region::text, 'NULL'),
                       quote_literal(p_objectkey), quote_literal(p_objectclass), quote_literal(p_version));
    IF v_solution IN ('average', 'manual') AND p_mesh IS NULL THEN
        RAISE EXCEPTION 'solution % of % needs the region''s mesh', v_solution, v_object
            USING ERRCODE = 'TG100',
                  HINT = 'give the mesh as the sixth argument (an .npz of a MeshState: tgsis.resolve_region in Python builds it)';
    END IF;
    IF v_solution NOT IN ('average', 'manual') AND p_mesh IS NOT NULL THEN
        RAISE EXCEPTION 'solution % of % takes no mesh: one was given', v_solution, v_object
            USING ERRCODE = 'TG100', HINT = 'leave the sixth argument out, or give the solution manual with the mesh';
    END IF;
    IF p_mesh IS NOT NULL AND substr(p_mesh, 1, 4) <> '\x504b0304'::bytea THEN
        RAISE EXCEPTION 'the mesh of % is no .npz file (a zip archive): it starts with %', v_object,
                encode(substr(p_mesh, 1, 8), 'hex')
            USING ERRCODE = 'TG100', HINT = 'give the bytes numpy.savez writes of a MeshState (tgsis.resolve_region in Python builds them)';
    END IF;
    IF num_nulls(p_vertex_ids, p_vertices, p_cell_ids, p_cells, p_vertex_columns, p_vertex_values, p_cell_columns,
                 p_cell_values) NOT IN (0, 8) OR (p_vertex_ids IS NOT NULL AND p_mesh IS NULL) THEN
        RAISE EXCEPTION 'the rows of the mesh of % are given in part: ids, coordinates, cells, columns and values go together, with the mesh',
                v_object
            USING ERRCODE = 'TG100', HINT = 'give all eight arrays after the mesh, or none';
    END IF;
    IF p_vertex_ids IS NOT NULL AND (
           cardinality(p_vertices) <> 3 * cardinality(p_vertex_ids)
           OR cardinality(p_cells) % greatest(cardinality(p_cell_ids), 1) <> 0
           OR cardinality(p_vertex_values) <> cardinality(p_vertex_columns) * cardinality(p_vertex_ids)
           OR cardinality(p_cell_values) <> cardinality(p_cell_columns) * cardinality(p_cell_ids)
           OR array_position(p_vertex_ids, NULL) IS NOT NULL OR array_position(p_cell_ids, NULL) IS NOT NULL
           OR array_position(p_cells, NULL) IS NOT NULL
           OR EXISTS (SELECT FROM unnest(p_vertices) AS u(x) WHERE x IS NULL OR x IN ('NaN', 'Infinity', '-Infinity'))) THEN
        RAISE EXCEPTION 'the rows of the mesh of % do not fit together: % vertex ids, % coordinates, % cell ids, % cell vertex ids, % vertex values of % columns, % cell values of % columns (or a NULL id, a non-finite coordinate)',
                v_object, cardinality(p_vertex_ids), cardinality(p_vertices), cardinality(p_cell_ids), cardinality(p_cells),
                cardinality(p_vertex_values), cardinality(p_vertex_columns), cardinality(p_cell_values), cardinality(p_cell_columns)
            USING ERRCODE = 'TG100', HINT = 'three coordinates per vertex, k vertex ids per cell, one value per column per row';
    END IF;
    IF p_vertex_ids IS NOT NULL AND cardinality(p_cell_ids) > 0 THEN  -- a cell on one vertex twice is no mesh's
        SELECT string_agg(c.id::text, ', ' ORDER BY c.o) INTO v_object_bad
          FROM unnest(p_cell_ids) WITH ORDINALITY AS c(id, o)
         WHERE (SELECT count(*) <> count(DISTINCT x)
                  FROM unnest(p_cells[(c.o - 1) * (cardinality(p_cells) / cardinality(p_cell_ids)) + 1
                                      : c.o * (cardinality(p_cells) / cardinality(p_cell_ids))]) AS x);
        IF v_object_bad IS NOT NULL THEN
            RAISE EXCEPTION 'the rows of the mesh of % are no mesh: cells % use a vertex twice', v_object, v_object_bad
                USING ERRCODE = 'TG100', HINT = 'give each cell k distinct vertex ids';
        END IF;
    END IF;
    IF p_vertex_ids IS NOT NULL THEN  -- the two copies of one mesh: the .npz (Python merge) and the rows (psql merge)
        v_object_bad := tgsis.npz_rows_differ(p_mesh, p_vertex_ids, p_vertices, p_cell_ids, p_cells, p_vertex_columns,
                                              p_vertex_values, p_cell_columns, p_cell_values);
        IF v_object_bad IS NOT NULL THEN
            RAISE EXCEPTION 'the rows of the mesh of % are not those of its .npz: %', v_object, v_object_bad
                USING ERRCODE = 'TG100',
                      HINT = 'give the rows of the mesh the .npz holds (tgsis.resolve_region in Python records both from one mesh)';
        END IF;
    END IF;
    IF p_region IS NULL THEN
        RAISE EXCEPTION 'the region of object % of class % in version % is NULL', quote_literal(p_objectkey),
                quote_literal(p_objectclass), quote_literal(p_version)
            USING ERRCODE = 'TG100', HINT = 'give the region''s number, as tgsis.conflict_regions lists it';
    END IF;
    PERFORM tgsis.require_version_privilege(v_id, 'write', 'resolve conflicts of');
    v_key := (tgsis.canonical_object_keys(p_objectclass, ARRAY[p_objectkey]))[1];
    IF v_solution IN ('average', 'manual') AND p_objectclass = 'feature' THEN
        -- the rows of the mesh are the role's own: the merge (maybe another role's) writes them into the
        -- version and the parent, so only a role that may change the feature gives them (42501 otherwise)
        PERFORM tgsis.check_class_write(ARRAY[v_key::bigint], 'UPDATE');
    END IF;
    -- the marks the region was found on: find_conflicts below finds the regions again on new marks (in
    -- SQL) when either side changed the object since, and a region of that number is then another one
    SELECT ARRAY[childmark, parentmark] INTO v_marks FROM tgsis.conflict_regions
     WHERE versionid = v_id AND objectclass = p_objectclass AND objectkey = v_key AND region = p_region;
    v_stored := FOUND;
    -- the marks must be those of now: regions found on an older state are removed
    v_detect := current_setting('tgsis.region_detection', true);
    PERFORM set_config('tgsis.region_detection', 'client', true);  -- (not a function SET: only a superuser may
    -- create a function that sets a parameter tgsis does not define)
    PERFORM tgsis.find_conflicts(p_version);
    PERFORM set_config('tgsis.region_detection', coalesce(v_detect, ''), true);
    IF p_objectclass = 'feature' THEN  -- found again in SQL on the marks of now (this object's only)
        PERFORM tgsis.store_mesh_regions(p_version, v_key);
    END IF;
    SELECT * INTO v_row FROM tgsis.conflict_regions
     WHERE versionid = v_id AND objectclass = p_objectclass AND objectkey = v_key AND region = p_region
       FOR UPDATE;
    IF (NOT FOUND AND v_stored) OR (FOUND AND v_stored AND ARRAY[v_row.childmark, v_row.parentmark] <> v_marks) THEN
        RAISE EXCEPTION '% was found on a state that changed since: the object changed in the version or its parent',
                v_object
            USING ERRCODE = 'TG307',
                  HINT = 'find the regions again (tgsis.find_conflicts in Python, or tgsis version conflicts), then solve them';
    ELSIF NOT FOUND THEN
        RAISE EXCEPTION '% is not a stored region: %', v_object,
                coalesce((SELECT format('the object has regions 0 to %s', max(region)) FROM tgsis.conflict_regions
                           WHERE versionid = v_id AND objectclass = p_objectclass AND objectkey = v_key HAVING count(*) > 0),
                         'no regions of the object are stored')
            USING ERRCODE = 'TG200',
                  HINT = format('SELECT region, conflict, solution FROM tgsis.conflict_regions WHERE versionid = tgsis.version_id(%L) lists them; tgsis.find_conflicts in Python finds them',
                                p_version);
    END IF;
    IF NOT v_row.conflict THEN
        RAISE EXCEPTION '% is not a conflict: only the % changed it, it merges by itself (automatic)', v_object,
                CASE v_row.changed_by WHEN 'both' THEN 'two sides, alike,' WHEN 'parent' THEN 'parent' ELSE 'version' END
            USING ERRCODE = 'TG307',
                  DETAIL = 'A solution there would drop the other side''s edit nobody needs to choose against.',
                  HINT = format('only a region with conflict = true takes a solution: SELECT region FROM tgsis.conflict_regions WHERE versionid = tgsis.version_id(%L) AND conflict',
                                p_version);
    END IF;
    UPDATE tgsis.conflict_regions
       SET solution = v_solution,
           solution_mesh = p_mesh,
           (solution_vertex_ids, solution_vertices, solution_cell_ids, solution_cells, solution_vertex_columns,
            solution_vertex_values, solution_cell_columns, solution_cell_values)
             = (SELECT p_vertex_ids, p_vertices, p_cell_ids, p_cells, p_vertex_columns, p_vertex_values, p_cell_columns,
                       p_cell_values),
           solved_at = CASE WHEN v_solution <> 'unsolved' THEN now() END,
           solved_by = CASE WHEN v_solution <> 'unsolved' THEN tgsis.calling_role() END
     WHERE versionid = v_id AND objectclass = p_objectclass AND objectkey = v_key AND region = p_region
    RETURNING * INTO v_row;
    RETURN v_row;
END
$$;

COMMENT ON FUNCTION tgsis.resolve_region(text, text, text, integer, text, bytea, bigint[], float8[], bigint[], bigint[], text[], float8[], text[], float8[]) IS
    'record the solution of one conflicting region of a mesh: parent, child, base (that state''s rows), average or manual (with the region''s mesh, and its rows in a form SQL reads for the psql merge), or unsolved; refused (TG307) for a region that is no conflict or was found on a state that changed since';
