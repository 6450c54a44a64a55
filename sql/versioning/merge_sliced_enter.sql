-- tgsis.merge_sliced_enter(version, geoid, versionid, feature columns, how): the rights, the version's working revision and the object's lock a psql merge of a temporal surface writes under.
-- Shared by tgsis.merge_instants_by_slice and tgsis.merge_periods_by_slice,
-- before their writes: the rights the Python merge's writes meet
-- (tgsis.merge_write_rights: TG002, 42501), the session put in the version's
-- working revision for this transaction (tgsis.goto_version; p_settings: the
-- session's settings before, for tgsis.merge_sliced_leave), the revision and
-- the working set written in, the object checked unlocked and locked for
-- writing, as the Python writer does.
CREATE FUNCTION tgsis.merge_sliced_enter(p_version text, p_geoid bigint, p_versionid integer, p_fcols text[], p_how text,
                                         OUT p_settings text[], OUT p_revision integer, OUT p_workingset integer[])
LANGUAGE plpgsql
VOLATILE
SET search_path = pg_catalog, pg_temp
AS $$
BEGIN
    PERFORM tgsis.merge_write_rights(p_version, p_geoid, p_fcols, p_how, 'surface');
    p_settings := ARRAY[current_setting('tgsis.version', true), current_setting('tgsis.revision', true)];
    PERFORM tgsis.goto_version(p_version, true);
    SELECT v.workingrevision, v.workingset INTO p_revision, p_workingset FROM tgsis.versions v WHERE v.versionid = p_versionid;
    PERFORM tgsis.check_objects_unlocked(t.objectclass, ARRAY[p_geoid::text])
       FROM tgsis.versioned_tables t WHERE t.schemaname = 'tgsis' AND t.tablename = 'geometry';
    PERFORM tgsis.object_write_lock('feature', ARRAY[p_geoid::text]);
END
$$;

-- internal to the psql merges, not executable by PUBLIC (tests/test_function_grants.py)
REVOKE ALL ON FUNCTION tgsis.merge_sliced_enter(text, bigint, integer, text[], text) FROM PUBLIC;

COMMENT ON FUNCTION tgsis.merge_sliced_enter(text, bigint, integer, text[], text) IS
    'before a psql merge of a temporal surface writes: the rights asked, the session in the version''s working revision (the settings before returned), the object checked unlocked and locked';
