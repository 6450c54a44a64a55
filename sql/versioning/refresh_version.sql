-- tgsis.refresh_version(version): bring the parent's changes since the version's base into it; returns the rows written.
-- The version's base moves to the parent's working revision (which is then
-- frozen): objects only the parent changed now look as in the parent, objects
-- only the version changed keep the version's state, and each conflicting
-- object follows its solution ('parent' takes the parent's object, 'child'
-- and 'manual' keep the version's; a NOTICE says what each discards).
-- First the unsolved conflicting meshes of static classes whose conflicting
-- regions all have a solution are merged by region into the version
-- (tgsis.merge_regions_in_sql, as the Python refresh does). Refused (TG302)
-- while a conflict is unsolved.
CREATE FUNCTION tgsis.refresh_version(p_version text)
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
    v_newset  integer[];
    v_next    integer;
    v_class   record;
    v_written bigint := 0;
    v_detect  text;
BEGIN
    PERFORM tgsis.require_merge_privileges(p_version, 'refresh');
    -- the unsolved conflicting meshes whose regions all have a solution are merged by region into the version
    -- first (tgsis.merge_regions_in_sql), as the Python merge does; the merge then copies them as 'manual'
    v_detect := current_setting('tgsis.region_detection', true);
    v_written := tgsis.merge_regions_in_sql(p_version, 'refresh', false);
    v_child := tgsis.lock_for_merge(p_version, 'refresh');
    SELECT * INTO v_parent FROM tgsis.versions WHERE versionid = v_child.parentid;
    PERFORM tgsis.notice_discards(p_version, 'refreshed');  -- what the solutions throw away, said before it is gone

    -- the parent's working revision becomes the new base; the version sees
    -- the parent's set up to it, its own revisions, and a new working one
    PERFORM tgsis.next_working_revision(v_parent.versionid);
    v_own := tgsis.own_working_revisions(v_child.versionid);
    v_next := tgsis.next_working_revision(v_child.versionid,
                                          ARRAY(SELECT DISTINCT r FROM unnest(v_parent.workingset || v_own) AS r ORDER BY r),
                                          v_parent.workingrevision);
    SELECT workingset INTO v_newset FROM tgsis.versions WHERE versionid = v_child.versionid;

    -- objects changed on both sides would now show both sides' rows: give each the state its solution says
    FOR v_class IN
        SELECT objectclass, solution = 'parent' AS take_parent, array_agg(objectkey) AS keys
          FROM tgsis.conflicts WHERE versionid = v_child.versionid
         GROUP BY 1, 2
    LOOP
        v_written := v_written + tgsis.copy_object_state(
            v_class.objectclass, v_class.keys,
            CASE WHEN v_class.take_parent THEN v_parent.workingset ELSE v_child.workingset END,
            v_newset, v_next);
    END LOOP;
    DELETE FROM tgsis.conflicts WHERE versionid = v_child.versionid;
    PERFORM set_config('tgsis.region_detection', coalesce(v_detect, ''), true);
    RETURN v_written;
END
$$;

COMMENT ON FUNCTION tgsis.refresh_version(text) IS
    'bring the parent''s changes since the version''s base into the version (its base moves to the parent''s working revision); conflicting objects follow their solutions, meshes changed on both sides merged by region first; refused while conflicts are unsolved; returns the rows written';
