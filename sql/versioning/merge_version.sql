-- tgsis.merge_version(version, remove): apply a version's changes to its parent's working revision; returns the rows written.
-- One transaction: for every object the version changed (except conflicts
-- solved 'parent') the parent is made to see the version's state, rows the
-- version did not change are not touched. The parent's working revision is
-- then frozen and a new one started. Without p_remove the version goes on
-- from the merged state (its base moves to that revision); with it, the
-- version is deleted. First the unsolved conflicting meshes of static
-- classes whose conflicting regions all have a solution are merged by
-- region into the version (tgsis.merge_regions_in_sql, as the Python merge
-- does). Refused (TG302) while a conflict is unsolved. A NOTICE
-- per solved conflict says what of the other side's edits its solution
-- discards (tgsis.notice_discards).
CREATE FUNCTION tgsis.merge_version(p_version text, p_remove boolean DEFAULT false)
RETURNS bigint
LANGUAGE plpgsql
VOLATILE
SECURITY DEFINER
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_child   tgsis.versions;
    v_parent  tgsis.versions;
    v_own     integer[];
    v_class   record;
    v_written bigint := 0;
    v_detect  text;
BEGIN
    -- the right to merge into the parent, and to change (or delete) the version itself, whose base moves
    PERFORM tgsis.require_merge_privileges(p_version, 'merge', coalesce(p_remove, false));
    IF coalesce(p_remove, false) AND EXISTS (SELECT FROM tgsis.versions WHERE parentid = tgsis.version_id(p_version)) THEN
        RAISE EXCEPTION 'version % has child versions and cannot be removed by the merge', quote_literal(p_version)
            USING ERRCODE = 'TG202', HINT = 'merge without removing it, or merge or delete its children first';
    END IF;
    -- the unsolved conflicting meshes whose regions all have a solution are merged by region into the version
    -- first (tgsis.merge_regions_in_sql), as the Python merge does; the merge then copies them as 'manual'
    v_detect := current_setting('tgsis.region_detection', true);
    v_written := tgsis.merge_regions_in_sql(p_version, 'merge', coalesce(p_remove, false));
    v_child := tgsis.lock_for_merge(p_version, 'merge');
    SELECT * INTO v_parent FROM tgsis.versions WHERE versionid = v_child.parentid;
    -- what the solutions throw away of the other side's edits, said before it is gone
    PERFORM tgsis.notice_discards(p_version, 'merged');

    v_own := tgsis.own_working_revisions(v_child.versionid);
    FOR v_class IN
        SELECT c.objectclass, array_agg(DISTINCT c.objectkey) AS keys
          FROM tgsis.changed_objects(v_own) AS c
         WHERE NOT EXISTS (SELECT FROM tgsis.conflicts k
                            WHERE k.versionid = v_child.versionid AND k.objectclass = c.objectclass
                              AND k.objectkey = c.objectkey AND k.solution = 'parent')
         GROUP BY c.objectclass
    LOOP
        -- an object another version locked stays as it is in the parent too
        PERFORM tgsis.check_objects_unlocked(v_class.objectclass, v_class.keys, v_child.versionid, false);
        -- the merge writes the objects' rows in the shared model tables: the merger needs the right to
        -- change the class of each feature (tgsis.check_class_write; 42501, nothing merged)
        IF v_class.objectclass = 'feature' THEN
            PERFORM tgsis.check_class_write(v_class.keys::bigint[], 'UPDATE');
        END IF;
        v_written := v_written + tgsis.copy_object_state(v_class.objectclass, v_class.keys, v_child.workingset,
                                                         v_parent.workingset, v_parent.workingrevision);
    END LOOP;

    -- the parent's working revision now holds the merge: freeze it, start the next
    PERFORM tgsis.next_working_revision(v_parent.versionid);

    IF coalesce(p_remove, false) THEN
        PERFORM tgsis.delete_version(p_version);
    ELSE
        -- the version goes on from the merged state: everything it had is in the parent now
        PERFORM tgsis.next_working_revision(v_child.versionid, v_parent.workingset, v_parent.workingrevision);
        DELETE FROM tgsis.conflicts WHERE versionid = v_child.versionid;
    END IF;
    PERFORM set_config('tgsis.region_detection', coalesce(v_detect, ''), true);
    RETURN v_written;
END
$$;

COMMENT ON FUNCTION tgsis.merge_version(text, boolean) IS
    'apply a version''s changes (object by object, unchanged rows untouched) to its parent''s working revision in one transaction, meshes changed on both sides merged by region first; refused while conflicts are unsolved; the version goes on from the merged state, or is removed; returns the rows written';
