-- tgsis.goto_revision(version, revision, local): look at an older revision of a version's history (read-only).
CREATE FUNCTION tgsis.goto_revision(p_version text, p_revision integer, p_local boolean DEFAULT false)
RETURNS integer
LANGUAGE plpgsql
VOLATILE
AS $$
BEGIN
    IF p_revision IS NULL THEN
        RAISE EXCEPTION 'goto_revision needs a revision' USING ERRCODE = 'TG100';
    END IF;
    PERFORM tgsis.revision_set(tgsis.version_id(p_version), p_revision);  -- TG200 unless in its history
    PERFORM set_config('tgsis.version', p_version, coalesce(p_local, false));
    PERFORM set_config('tgsis.revision', p_revision::text, coalesce(p_local, false));
    RETURN p_revision;
END
$$;

COMMENT ON FUNCTION tgsis.goto_revision(text, integer, boolean) IS
    'look at revision r of a version''s history (read-only until goto_version): its working set, or its own older revisions';
