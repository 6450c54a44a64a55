-- tgsis.merge_sliced_leave(version, geoid, settings, solved): the session's settings put back after a psql merge of a temporal surface wrote (or took back) its rows, and the conflict recorded 'manual' when solved.
-- The end of tgsis.merge_instants_by_slice and tgsis.merge_periods_by_slice,
-- the counterpart of tgsis.merge_sliced_enter: the session's version and
-- revision settings as they were (p_settings), then, when the merged rows
-- were written (p_solved), the object's conflict recorded 'manual' so that
-- the merge merges it as any solved object, as the Python merge records it.
CREATE FUNCTION tgsis.merge_sliced_leave(p_version text, p_geoid bigint, p_settings text[], p_solved boolean)
RETURNS void
LANGUAGE plpgsql
VOLATILE
SET search_path = pg_catalog, pg_temp
AS $$
BEGIN
    PERFORM set_config('tgsis.version', coalesce(p_settings[1], ''), true),
            set_config('tgsis.revision', coalesce(p_settings[2], ''), true);
    IF p_solved THEN
        PERFORM FROM tgsis.resolve_conflict(p_version, 'feature', p_geoid::text, 'manual');
    END IF;
END
$$;

-- internal to the psql merges, not executable by PUBLIC (tests/test_function_grants.py)
REVOKE ALL ON FUNCTION tgsis.merge_sliced_leave(text, bigint, text[], boolean) FROM PUBLIC;

COMMENT ON FUNCTION tgsis.merge_sliced_leave(text, bigint, text[], boolean) IS
    'after a psql merge of a temporal surface wrote its rows: the session''s version settings put back, the conflict recorded manual when solved';
