-- tgsis.store_mesh_regions(version, objectkey): find and store, in SQL, the regions of one conflicting mesh that has none stored.
-- Called by tgsis.find_conflicts (for each unsolved conflicting feature) and
-- tgsis.resolve_conflict (for the object it solves, whatever its solution
-- was: the rule that refuses a whole side dropping the other side's edits
-- needs them), as tgsis's owner, after the conflicts and their marks were
-- stored. It stores nothing when regions are stored already (on the current
-- marks: find_conflicts removed stale ones), when the calling role may not
-- read the feature's class (the Python client would not read it either),
-- or when the feature does not merge by region (tgsis.region_merge_refusal,
-- or mesh_merge_regions' TG100: new ids that cannot be renumbered within
-- bigint; or its TG302: a NaN or infinite coordinate among the rows read,
-- whose merge tgsis.merge_mesh_by_region refuses), so that one such feature
-- does not make find_conflicts fail.
-- A surface at instants (model 2) or an evolving surface (model 3): the rows of
-- tgsis.instants_merge_regions (each with its slice: the instant or geometry instant, times, and the
-- period, timem; numbered through the object), none for an object-level conflict (or a model-3 object
-- no solution merges: TG308), as the Python find_conflicts stores them; none when the calling role may
-- not read one of the class's property views (the Python find_conflicts cannot read their rows).
-- Otherwise the rows of tgsis.mesh_merge_regions go in as found: a conflict
-- unsolved, the others automatic. Returns the regions stored.
CREATE FUNCTION tgsis.store_mesh_regions(p_version text, p_objectkey text)
RETURNS integer
LANGUAGE plpgsql
VOLATILE
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_row     tgsis.conflicts;
    v_count   integer;
    v_instants boolean;
BEGIN
    SELECT * INTO v_row FROM tgsis.conflicts k
     WHERE k.versionid = tgsis.version_id(p_version) AND k.objectclass = 'feature' AND k.objectkey = p_objectkey;
    IF NOT FOUND
       OR EXISTS (SELECT FROM tgsis.conflict_regions r WHERE r.versionid = v_row.versionid
                     AND r.objectclass = 'feature' AND r.objectkey = p_objectkey)
       OR p_objectkey::bigint IN (SELECT tgsis.class_denied_geoids('SELECT')) THEN
        RETURN 0;
    END IF;
    v_instants := (SELECT c.timemodel FROM tgsis.catalog c WHERE c.classname = tgsis.class_of_geoid(p_objectkey::bigint))
                  IN ('INSTANTS', 'EVOLVING');
    IF v_instants THEN  -- a surface at instants, an evolving surface: the regions of its slices, numbered through the object
        -- a property view of the class the calling role may not read: the Python find_conflicts cannot read its rows
        -- (MissingPrivilegeError: no regions, the refusal said), so none are found here either (the owner reads them)
        IF EXISTS (SELECT FROM tgsis.catalog c
                    CROSS JOIN LATERAL unnest(ARRAY[c.cellprotable, c.otherprotable]
                                              || CASE WHEN jsonb_array_length(c.instant_properties) > 0
                                                      THEN ARRAY[c.protablename] ELSE '{}'::text[] END) AS t (name)
                    WHERE c.classname = tgsis.class_of_geoid(p_objectkey::bigint) AND t.name IS NOT NULL
                      AND pg_catalog.to_regclass(format('%I.%I', c.schemaname, t.name)) IS NOT NULL
                      AND NOT has_table_privilege(tgsis.calling_role(), format('%I.%I', c.schemaname, t.name)::regclass,
                                                  'SELECT')) THEN
            RETURN 0;
        END IF;
        BEGIN
            INSERT INTO tgsis.conflict_regions (versionid, objectclass, objectkey, region, childmark, parentmark, conflict,
                                                changed_by, vertex_ids, cell_ids, parent_vertex_ids, parent_cell_ids,
                                                child_vertex_ids, child_cell_ids, bbox, parent_displacement,
                                                child_displacement, solution, times, timem)
            SELECT v_row.versionid, 'feature', p_objectkey, m.region, v_row.childmark, v_row.parentmark, m.conflict,
                   m.changed_by, m.vertex_ids, m.cell_ids, m.parent_vertex_ids, m.parent_cell_ids, m.child_vertex_ids,
                   m.child_cell_ids, m.bbox, m.parent_displacement, m.child_displacement,
                   CASE WHEN m.conflict THEN 'unsolved' ELSE 'automatic' END, m.times, m.timem
              FROM tgsis.instants_merge_regions(p_version, p_objectkey::bigint) AS m;
            GET DIAGNOSTICS v_count = ROW_COUNT;
        EXCEPTION WHEN SQLSTATE 'TG100' OR SQLSTATE 'TG302' THEN
            -- an object-level conflict (or TG308), new ids beyond bigint, non-finite coordinates: no regions, as in Python
            RETURN 0;
        END;
        RETURN v_count;
    END IF;
    IF tgsis.region_merge_refusal(p_version, p_objectkey::bigint) IS NOT NULL THEN
        RETURN 0;
    END IF;
    BEGIN
        INSERT INTO tgsis.conflict_regions (versionid, objectclass, objectkey, region, childmark, parentmark, conflict,
                                            changed_by, vertex_ids, cell_ids, parent_vertex_ids, parent_cell_ids,
                                            child_vertex_ids, child_cell_ids, bbox, parent_displacement,
                                            child_displacement, solution)
        SELECT v_row.versionid, 'feature', p_objectkey, m.region, v_row.childmark, v_row.parentmark, m.conflict,
               m.changed_by, m.vertex_ids, m.cell_ids, m.parent_vertex_ids, m.parent_cell_ids, m.child_vertex_ids,
               m.child_cell_ids, m.bbox, m.parent_displacement, m.child_displacement,
               CASE WHEN m.conflict THEN 'unsolved' ELSE 'automatic' END
          FROM tgsis.mesh_merge_regions(p_version, p_objectkey::bigint) AS m;
        GET DIAGNOSTICS v_count = ROW_COUNT;
    EXCEPTION WHEN SQLSTATE 'TG100' OR SQLSTATE 'TG302' THEN
        -- it does not merge by region after all (new ids beyond bigint; non-finite coordinates, which
        -- tgsis.mesh_merge_regions refuses as tgsis.merge_mesh_by_region does): nothing stored
        RETURN 0;
    END;
    RETURN v_count;
END
$$;

COMMENT ON FUNCTION tgsis.store_mesh_regions(text, text) IS
    'find (tgsis.mesh_merge_regions) and store the regions of one conflicting feature of a version that has none stored, when the calling role may read its class and it merges by region; returns the regions stored';

-- internal to the merges: reached only through the SECURITY DEFINER merge, refresh, find_conflicts and
-- resolve functions, as their owner; not executable by PUBLIC (tests/test_function_grants.py)
REVOKE ALL ON FUNCTION tgsis.store_mesh_regions(text, text) FROM PUBLIC;
