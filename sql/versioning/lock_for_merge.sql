-- tgsis.lock_for_merge(version, action): lock a version and its parent for a merge or refresh; returns the version's row.
-- Parent first, then child (tgsis.lock_version_pair): the order every merge
-- and refresh takes, waiting for writers of either and for another merge or
-- refresh of either. Then the conflicts are recomputed: TG302 names the
-- unsolved ones.
CREATE FUNCTION tgsis.lock_for_merge(p_version text, p_action text)
RETURNS tgsis.versions
LANGUAGE plpgsql
VOLATILE
AS $$
DECLARE
    v_child tgsis.versions;
BEGIN
    v_child := tgsis.lock_version_pair(p_version, p_action);
    PERFORM tgsis.check_no_unsolved_conflicts(p_version, p_action);
    RETURN v_child;
END
$$;

COMMENT ON FUNCTION tgsis.lock_for_merge(text, text) IS
    'lock a version and its parent (parent first) for a merge or refresh, then refuse (TG302) while conflicts are unsolved; returns the version''s row';
