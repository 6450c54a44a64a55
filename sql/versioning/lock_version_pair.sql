-- tgsis.lock_version_pair(version, action): lock a version and its parent, parent first; returns the version's row.
-- The locking every merge and refresh takes, shared by tgsis.lock_for_merge
-- (which then refuses unsolved conflicts) and tgsis.lock_for_region_merge
-- (which does not: the merge by region solves some of them in the locked
-- transaction). FOR UPDATE on both rows waits for writers of either
-- (write_revision share-locks a version) and for another merge or refresh of
-- either. READ COMMITTED only: after the wait each statement must see what
-- the writers committed.
CREATE FUNCTION tgsis.lock_version_pair(p_version text, p_action text)
RETURNS tgsis.versions
LANGUAGE plpgsql
VOLATILE
AS $$
DECLARE
    v_child tgsis.versions;
BEGIN
    PERFORM tgsis.require_read_committed(p_action);
    SELECT * INTO v_child FROM tgsis.versions WHERE versionid = tgsis.version_id(p_version);
    IF v_child.parentid IS NULL THEN
        RAISE EXCEPTION 'version DEFAULT has no parent: nothing to %', p_action USING ERRCODE = 'TG100';
    END IF;
    PERFORM FROM tgsis.versions WHERE versionid = v_child.parentid FOR UPDATE;
    SELECT * INTO v_child FROM tgsis.versions WHERE versionid = v_child.versionid FOR UPDATE;
    IF NOT FOUND THEN
        -- a merge with remove (or delete_version) committed while this one waited: go
        -- no further with an empty row (a version re-created under the same name
        -- meanwhile is another version, and not the one asked for)
        RAISE EXCEPTION 'version % does not exist', quote_literal(p_version)
            USING ERRCODE = 'TG200', DETAIL = format('It was removed while this %s waited for it.', p_action);
    END IF;
    RETURN v_child;
END
$$;

COMMENT ON FUNCTION tgsis.lock_version_pair(text, text) IS
    'lock a version and its parent (parent first, waiting for their writers and merges) for a merge or refresh; returns the version''s row';
