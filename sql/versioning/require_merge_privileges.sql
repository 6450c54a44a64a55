-- tgsis.require_merge_privileges(version, action, remove): TG002 unless the calling role may merge or refresh the version.
-- One place for the rights of tgsis.merge_version, tgsis.refresh_version and
-- tgsis.lock_for_region_merge. A merge needs 'merge' on the parent and
-- 'write' on the version, whose base moves ('delete' instead when the merge
-- removes it); a refresh needs 'write' on the version. A version without a
-- parent (DEFAULT) is left to the locking, which says there is nothing to do.
CREATE FUNCTION tgsis.require_merge_privileges(p_version text, p_action text, p_remove boolean DEFAULT false)
RETURNS void
LANGUAGE plpgsql
STABLE
AS $$
BEGIN
    IF p_action = 'refresh' THEN
        PERFORM tgsis.require_version_privilege(tgsis.version_id(p_version), 'write', 'refresh');
    ELSIF p_action = 'merge' THEN
        PERFORM tgsis.require_version_privilege(parentid, 'merge', 'merge into'),
                tgsis.require_version_privilege(versionid, CASE WHEN p_remove THEN 'delete' ELSE 'write' END,
                                                CASE WHEN p_remove THEN 'delete' ELSE 'write in' END)
           FROM tgsis.versions WHERE versionid = tgsis.version_id(p_version) AND parentid IS NOT NULL;
    ELSE
        RAISE EXCEPTION 'action % is neither merge nor refresh', coalesce(quote_literal(p_action), 'NULL')
            USING ERRCODE = 'TG100';
    END IF;
END
$$;

COMMENT ON FUNCTION tgsis.require_merge_privileges(text, text, boolean) IS
    'raise TG002 unless the calling role may merge (merge on the parent, write or with remove delete on the version) or refresh (write on the version) a version';

-- internal to the merges: reached only through the SECURITY DEFINER merge, refresh, find_conflicts and
-- resolve functions, as their owner; not executable by PUBLIC (tests/test_function_grants.py)
REVOKE ALL ON FUNCTION tgsis.require_merge_privileges(text, text, boolean) FROM PUBLIC;
