-- tgsis.write_revision(check_rights): the revision and revision set a write of this session uses, or TG301/TG002 if it may not write.
-- It share-locks the version's row until the transaction ends, so that
-- create_version and save_revision (which lock it for update) never hand the
-- working revision on while a writer is still labelling rows with it.
-- p_check_rights false skips the write-right check: the row triggers of the
-- views pass it, because a statement trigger on each view made that check
-- once for the statement (per row it doubled the cost of a write).
CREATE FUNCTION tgsis.write_revision(p_check_rights boolean DEFAULT true, OUT revision integer, OUT revisions integer[])
LANGUAGE plpgsql
VOLATILE
SECURITY DEFINER
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_name    text := tgsis.get_working_version();
    v_viewing integer := tgsis.get_viewing_revision();
    v_saved   text;
    v_id      integer;
BEGIN
    SELECT v.versionid, v.workingrevision, v.workingset INTO v_id, revision, revisions
      FROM tgsis.versions v WHERE v.name = v_name
       FOR SHARE;
    IF NOT FOUND THEN
        RAISE EXCEPTION 'version % does not exist', quote_literal(v_name)
            USING ERRCODE = 'TG200', HINT = 'SELECT tgsis.goto_version(''DEFAULT'')';
    END IF;
    IF v_viewing IS NOT NULL AND v_viewing <> revision THEN
        SELECT r.name INTO v_saved FROM tgsis.revisions r WHERE r.revision = v_viewing;
        RAISE EXCEPTION 'version % is viewed at revision %, which cannot be changed', quote_literal(v_name), v_viewing
            USING ERRCODE = 'TG301',
                  DETAIL = CASE WHEN v_saved IS NOT NULL
                                THEN format('Revision %s was saved as %L and is frozen; only the working revision %s of %s can change.',
                                            v_viewing, v_saved, revision, v_name)
                                ELSE format('Only the working revision %s of %s can change.', revision, v_name) END,
                  HINT = format('SELECT tgsis.goto_version(%L) to work in its working revision', v_name);
    END IF;
    IF p_check_rights THEN
        PERFORM tgsis.require_version_privilege(v_id, 'write', 'write in');
    END IF;
END
$$;

COMMENT ON FUNCTION tgsis.write_revision(boolean) IS
    'working revision and working set for a write in the session''s version; TG301 while an older revision is viewed, TG002 without the write right (unless p_check_rights is false: the check was made for the statement); share-locks the version until commit';
