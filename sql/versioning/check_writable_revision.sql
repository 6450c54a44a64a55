-- tgsis.check_writable_revision(version, working revision): TG301 while the session views a revision other than the working one.
-- Shared by the write paths (tgsis.write_revision) and save_revision, which
-- must refuse before they lock or write anything.
CREATE FUNCTION tgsis.check_writable_revision(p_version text, p_working integer)
RETURNS void
LANGUAGE plpgsql
STABLE
AS $$
DECLARE
    v_viewing integer := tgsis.get_viewing_revision();  -- TG100 for a malformed setting
    v_saved   text;
BEGIN
    IF v_viewing IS NULL OR v_viewing = p_working THEN
        RETURN;
    END IF;
    SELECT r.name INTO v_saved FROM tgsis.revisions r WHERE r.revision = v_viewing;
    RAISE EXCEPTION 'version % is viewed at revision %, which cannot be changed', quote_literal(p_version), v_viewing
        USING ERRCODE = 'TG301',
              DETAIL = CASE WHEN v_saved IS NOT NULL
                            THEN format('Revision %s was saved as %L and is frozen; only the working revision %s of %L can change.',
                                        v_viewing, v_saved, p_working, p_version)
                            ELSE format('Only the working revision %s of %L can change.', p_working, p_version) END,
              HINT = format('SELECT tgsis.goto_version(%L) to work in its working revision', p_version);
END
$$;

COMMENT ON FUNCTION tgsis.check_writable_revision(text, integer) IS
    'raise TG301 (naming the viewed revision, and its name when saved) while the session views a revision of the version other than its working revision';
