-- tgsis.revision_set(versionid, revision): the revision set of (version, revision), or TG200 when the revision is not in its history.
-- The working revision sees the version's working set; any other revision of
-- its history sees what its version saw while it was working (stored when it
-- was frozen). The history is the working set plus the version's own older
-- revisions (merge and refresh move a version's base, not its past).
-- PARALLEL SAFE: it only reads tables (tgsis.get_revisions calls it in
-- parallel workers).
CREATE FUNCTION tgsis.revision_set(p_versionid integer, p_revision integer)
RETURNS integer[]
LANGUAGE plpgsql
STABLE
PARALLEL SAFE
SECURITY DEFINER
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_version tgsis.versions;
    v_set     integer[];
BEGIN
    SELECT * INTO v_version FROM tgsis.versions WHERE versionid = p_versionid;
    IF p_revision IS NULL OR p_revision = v_version.workingrevision THEN
        RETURN v_version.workingset;
    END IF;
    SELECT r.visibleset INTO v_set FROM tgsis.revisions r
     WHERE r.revision = p_revision AND (r.revision = ANY (v_version.workingset) OR r.versionid = p_versionid);
    IF v_set IS NULL THEN
        RAISE EXCEPTION 'revision % is not in the history of version %', p_revision, quote_literal(v_version.name)
            USING ERRCODE = 'TG200',
                  DETAIL = format('Version %L can look at revisions %s.', v_version.name,
                                  (SELECT string_agg(h.revision::text, ', ' ORDER BY h.revision) FROM tgsis.revisions h
                                    WHERE h.revision = ANY (v_version.workingset) OR h.versionid = p_versionid)),
                  HINT = 'a version sees its own revisions and its ancestors'' revisions up to the moment it was based on them';
    END IF;
    RETURN v_set;
END
$$;

COMMENT ON FUNCTION tgsis.revision_set(integer, integer) IS
    'revision set of (version, revision): the working set for the working revision, the stored set of a frozen revision of its history; TG200 otherwise';
