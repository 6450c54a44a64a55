-- tgsis.lock_for_region_merge(version, action, remove): the rights and locks of a merge or refresh, without refusing conflicts.
-- The first step of a merge (or refresh) by region (tgsis.merge_version in
-- Python, docs/merge.md): it checks the rights tgsis.merge_version
-- (action 'merge', p_remove as there) or tgsis.refresh_version ('refresh')
-- checks, and takes their locks (tgsis.lock_version_pair: parent, then
-- version, waiting for writers of either), but does not refuse unsolved
-- conflicts: in the same READ COMMITTED transaction the client reads the
-- three states of each conflicting mesh (no writer of either side can
-- commit meanwhile), writes the merged mesh into the version, records it
-- 'manual', and then runs tgsis.merge_version / tgsis.refresh_version, which
-- refuse (TG302) whatever is still unsolved. The locks are held until the
-- transaction ends.
CREATE FUNCTION tgsis.lock_for_region_merge(p_version text, p_action text, p_remove boolean DEFAULT false)
RETURNS tgsis.versions
LANGUAGE plpgsql
VOLATILE
SECURITY DEFINER
SET search_path = pg_catalog, pg_temp
AS $$
BEGIN
    PERFORM tgsis.require_merge_privileges(p_version, p_action, coalesce(p_remove, false));
    RETURN tgsis.lock_version_pair(p_version, p_action);
END
$$;

COMMENT ON FUNCTION tgsis.lock_for_region_merge(text, text, boolean) IS
    'check the rights of a merge (merge) or refresh (refresh) of a version and take its locks (parent, then version) without refusing unsolved conflicts: the first step of a merge by region in one READ COMMITTED transaction; returns the version''s row';
