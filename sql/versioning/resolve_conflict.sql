-- tgsis.resolve_conflict(version, objectclass, objectkey, solution): record how a conflicting object is to be merged.
-- parent: keep the parent's object; child: take the version's; manual: the
-- version already holds the merged object (write it there first). The
-- solution holds for the current state of both sides (find_conflicts sets
-- it back to unsolved when either changes the object again). The key is
-- read in the key column's type with the session's settings
-- (tgsis.canonical_object_keys): '02/01/2024' under DateStyle DMY names the
-- conflict of 2024-01-02. A NOTICE says what the solution discards of the
-- other side's edits (tgsis.conflict_discards). A mesh's regions are found
-- first when none are stored (tgsis.store_mesh_regions, in SQL: no client
-- needed; a role that may not read the feature's class gets none computed,
-- and its parent or child is refused, 42501, until they are stored), and
-- parent and child are refused
-- (TG307) if the other side has edits in a region that is no conflict:
-- tgsis.resolve_region solves the conflicting regions, the merge keeps the rest.
-- base: the object as the version was based on it (its initial revision's
-- state, attributes included) is written into the version
-- (tgsis.copy_object_state: only the rows that differ) and the conflict
-- recorded manual; a NOTICE first says what it discards of each side's
-- edits (both are lost). It is refused (TG307) when the regions are stored
-- and one merges by itself: it would drop that side's edit, which
-- tgsis.resolve_region(..., 'base') per conflicting region (the Python
-- tgsis.resolve_all_regions(..., 'base')) does not. average is computed in
-- Python (the average shape of two meshes): refused here (TG100), the hint
-- naming the command.
-- Its find_conflicts (the marks of now) finds no other object's regions
-- (tgsis.region_detection = 'client' around it): it finds its own
-- (tgsis.store_mesh_regions), so that solving n conflicts one by one does
-- not try every other unsolved mesh n times.
CREATE FUNCTION tgsis.resolve_conflict(p_version text, p_objectclass text, p_objectkey text, p_solution text)
RETURNS tgsis.conflicts
LANGUAGE plpgsql
VOLATILE
SECURITY DEFINER
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_detect text;
    v_id  integer := tgsis.version_id(p_version);
    v_row tgsis.conflicts;
    v_key text := (tgsis.canonical_object_keys(p_objectclass, ARRAY[p_objectkey]))[1];
    v_lost text;
BEGIN
    IF p_solution IS NULL OR lower(p_solution) NOT IN ('parent', 'child', 'base', 'average', 'manual', 'unsolved') THEN
        RAISE EXCEPTION 'solution % is not parent, child, base, average, manual or unsolved', coalesce(quote_literal(p_solution), 'NULL')
            USING ERRCODE = 'TG100';
    END IF;
    IF lower(p_solution) = 'average' AND p_objectclass <> 'feature' THEN
        RAISE EXCEPTION 'solution average is the average shape of a feature''s two meshes: object % of class % in version % is a row of a versioned table',
                quote_literal(p_objectkey), quote_literal(p_objectclass), quote_literal(p_version)
            USING ERRCODE = 'TG100', HINT = 'solve it with parent, child, base or manual';
    ELSIF lower(p_solution) = 'average' THEN
        RAISE EXCEPTION 'solution average of object % of class % in version % is computed by the Python library, not in SQL',
                quote_literal(p_objectkey), quote_literal(p_objectclass), quote_literal(p_version)
            USING ERRCODE = 'TG100',
                  DETAIL = 'The average is the morphological average shape of the two sides'' meshes (numpy), written into the version and recorded manual.',
                  HINT = format('tgsis version resolve %s %s %s average', tgsis.shell_quote(p_version),
                                tgsis.shell_quote(p_objectclass), tgsis.shell_quote(v_key));
    END IF;
    PERFORM tgsis.require_version_privilege(v_id, 'write', 'resolve conflicts of');
    -- the marks must be those of now: a manual solution is written just before it is recorded
    v_detect := current_setting('tgsis.region_detection', true);
    PERFORM set_config('tgsis.region_detection', 'client', true);  -- (not a function SET: only a superuser may
    -- create a function that sets a parameter tgsis does not define)
    PERFORM tgsis.find_conflicts(p_version);
    PERFORM set_config('tgsis.region_detection', coalesce(v_detect, ''), true);
    IF p_objectclass = 'feature' AND lower(p_solution) IN ('parent', 'child', 'base') THEN
        -- its regions first (in SQL if nobody found them: a psql user runs no Python): base drops every
        -- side's edits, and parent or child is checked against the other side's below
        PERFORM tgsis.store_mesh_regions(p_version, v_key);
        IF lower(p_solution) <> 'base' AND v_key::bigint IN (SELECT tgsis.class_denied_geoids('SELECT'))
           AND NOT EXISTS (SELECT FROM tgsis.conflict_regions r
                            WHERE r.versionid = v_id AND r.objectclass = 'feature' AND r.objectkey = v_key)
           AND tgsis.region_merge_refusal(p_version, v_key::bigint) IS NULL THEN
            -- the regions are found with the caller's rights: none for a role kept from the class, and
            -- unchecked, its whole side could drop the other side's edits in regions that merge by themselves
            RAISE EXCEPTION 'role % may not read feature % (its class): whether solution % drops the % edits in regions that are no conflict cannot be checked',
                    quote_ident(tgsis.calling_role()), v_key, lower(p_solution),
                    CASE lower(p_solution) WHEN 'parent' THEN 'version''s' ELSE 'parent''s' END
                USING ERRCODE = '42501',
                      HINT = format('a role that may read the class finds its regions with SELECT FROM tgsis.find_conflicts(%L), or the class''s owner lets this role read it',
                                    p_version);
        END IF;
    END IF;
    IF lower(p_solution) = 'base' THEN
        PERFORM tgsis.resolve_conflict_base(p_version, p_objectclass, p_objectkey, v_key);
        p_solution := 'manual';  -- the version holds the base's object now
    END IF;
    -- a mesh whose regions are stored (current marks: find_conflicts just dropped older ones): one side's
    -- whole object would drop the other side's edits in regions that merge by themselves
    IF lower(p_solution) IN ('parent', 'child') THEN
        -- models 2 and 3 first (the message names the slices): a slice only the other side changed merges by
        -- itself (an instant moved, added or removed on that side alone), which the whole object would drop
        IF p_objectclass = 'feature' AND EXISTS (SELECT FROM tgsis.conflicts c WHERE c.versionid = v_id
                                                    AND c.objectclass = 'feature' AND c.objectkey = v_key) THEN
            v_lost := tgsis.slice_only_edits(p_version, v_key::bigint,
                                             CASE lower(p_solution) WHEN 'parent' THEN 'child' ELSE 'parent' END);
            IF v_lost IS NOT NULL THEN
                RAISE EXCEPTION 'solution % of object % of class % in version % would drop the % edits of %, which only that side changed',
                        lower(p_solution), quote_literal(p_objectkey), quote_literal(p_objectclass), quote_literal(p_version),
                        CASE lower(p_solution) WHEN 'parent' THEN 'version''s' ELSE 'parent''s' END, v_lost
                    USING ERRCODE = 'TG307',
                          DETAIL = 'A surface at instants merges instant by instant, an evolving surface geometry instant by geometry instant: a slice only one side changed merges by itself.',
                          HINT = format('tgsis version merge %s merges it slice by slice (tgsis version conflicts %s lists its regions, tgsis version resolve solves them); or record manual after writing the merged object',
                                        tgsis.shell_quote(p_version), tgsis.shell_quote(p_version));
            END IF;
        END IF;
        -- then a region only the other side changed (model 1, and the regions of a slice both sides changed)
        SELECT string_agg(r.region::text, ', ' ORDER BY r.region) INTO v_lost
          FROM tgsis.conflict_regions r
         WHERE r.versionid = v_id AND r.objectclass = p_objectclass AND r.objectkey = v_key AND NOT r.conflict
           AND r.changed_by = CASE lower(p_solution) WHEN 'parent' THEN 'child' ELSE 'parent' END;
        IF v_lost IS NOT NULL THEN
            RAISE EXCEPTION 'solution % of object % of class % in version % would drop the % edits in regions % that are no conflict',
                    lower(p_solution), quote_literal(p_objectkey), quote_literal(p_objectclass), quote_literal(p_version),
                    CASE lower(p_solution) WHEN 'parent' THEN 'version''s' ELSE 'parent''s' END, v_lost
                USING ERRCODE = 'TG307',
                      DETAIL = 'Only the other side changed those regions: the merge by region keeps those edits by itself.',
                      HINT = format('solve the conflicting regions with SELECT tgsis.resolve_region(%L, %L, %L, region, ''%s''); the merge takes the rest by itself (or record manual after writing the merged object)',
                                    p_version, p_objectclass, v_key, lower(p_solution));
        END IF;
    END IF;
    UPDATE tgsis.conflicts
       SET solution = lower(p_solution),
           solved_at = CASE WHEN lower(p_solution) <> 'unsolved' THEN now() END,
           solved_by = CASE WHEN lower(p_solution) <> 'unsolved' THEN tgsis.calling_role() END
     WHERE versionid = v_id AND objectclass = p_objectclass AND objectkey = v_key
    RETURNING * INTO v_row;
    IF NOT FOUND THEN
        RAISE EXCEPTION 'object % of class % is not in conflict in version %', quote_literal(p_objectkey),
                quote_literal(p_objectclass), quote_literal(p_version)
            USING ERRCODE = 'TG200', HINT = format('SELECT * FROM tgsis.find_conflicts(%L) lists the conflicts', p_version);
    END IF;
    -- a solution takes one side's whole object: say what of the other side's edits it throws away
    PERFORM tgsis.notice_discards(p_version, 'recorded', p_objectclass, v_key);  -- the key as the conflicts name it
    RETURN v_row;
END
$$;

COMMENT ON FUNCTION tgsis.resolve_conflict(text, text, text, text) IS
    'record the solution of a conflicting object: parent (keep the parent''s), child (take the version''s), base (write the object as the version was based on it into the version, recorded manual), manual (the version holds the merged object), or unsolved; average is the Python library''s';
