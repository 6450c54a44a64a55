-- tgsis.next_working_revision(versionid, base, initrevision): freeze a version's working revision and hand it a new one.
-- The frozen revision keeps the set its version saw (revisions.visibleset),
-- which is what goto_revision shows later. With p_base the version is
-- re-based (merge, refresh): its new working set is p_base plus the new
-- revision and its initrevision p_initrevision. Returns the new revision.
-- The caller holds the version's row lock.
CREATE FUNCTION tgsis.next_working_revision(
    p_versionid    integer,
    p_base         integer[] DEFAULT NULL,
    p_initrevision integer   DEFAULT NULL)
RETURNS integer
LANGUAGE plpgsql
VOLATILE
AS $$
DECLARE
    v_version tgsis.versions;
    v_next    integer;
BEGIN
    SELECT * INTO v_version FROM tgsis.versions WHERE versionid = p_versionid;
    UPDATE tgsis.revisions SET visibleset = v_version.workingset WHERE revision = v_version.workingrevision;
    v_next := nextval('tgsis.revision_seq');
    INSERT INTO tgsis.revisions (revision, versionid, created_by) VALUES (v_next, p_versionid, tgsis.calling_role());
    UPDATE tgsis.versions
       SET workingrevision = v_next,
           workingset = coalesce(p_base, workingset) || v_next,
           initrevision = coalesce(p_initrevision, initrevision)
     WHERE versionid = p_versionid;
    RETURN v_next;
END
$$;

COMMENT ON FUNCTION tgsis.next_working_revision(integer, integer[], integer) IS
    'freeze a version''s working revision (storing the set it saw) and give it a new one, optionally re-based on p_base / p_initrevision; returns the new revision';
