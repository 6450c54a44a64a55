-- tgsis.own_working_revisions(versionid): the version's own revisions in its working set, ascending.
-- These hold its changes not yet merged: a merge re-bases the version and leaves the older ones behind.
CREATE FUNCTION tgsis.own_working_revisions(p_versionid integer)
RETURNS integer[]
LANGUAGE sql
STABLE
AS $$
    SELECT coalesce(array_agg(r.revision ORDER BY r.revision), '{}')
      FROM tgsis.revisions r JOIN tgsis.versions v ON v.versionid = r.versionid
     WHERE r.versionid = p_versionid AND r.revision = ANY (v.workingset)
$$;

COMMENT ON FUNCTION tgsis.own_working_revisions(integer) IS
    'a version''s own revisions in its working set (its changes since its base), ascending';
