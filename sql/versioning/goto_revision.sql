-- tgsis.goto_revision(version, revision, local): look at an older revision of a version's history (read-only).
CREATE FUNCTION tgsis.goto_revision(p_version text, p_revision integer, p_local boolean DEFAULT false)
RETURNS integer
LANGUAGE plpgsql
VOLATILE
AS $$
DECLARE
    v_set integer[];
BEGIN
    PERFORM tgsis.version_id(p_version);
    SELECT workingset INTO v_set FROM tgsis.versions WHERE name = p_version;
    IF p_revision IS NULL OR NOT p_revision = ANY (v_set) THEN
        RAISE EXCEPTION 'revision % is not in the history of version %', coalesce(p_revision::text, 'NULL'), quote_literal(p_version)
            USING ERRCODE = 'TG200',
                  DETAIL = format('Version %s can look at revisions %s.', p_version, array_to_string(v_set, ', ')),
                  HINT = 'a version sees its own revisions and its ancestors'' revisions up to the moment it was created';
    END IF;
    PERFORM set_config('tgsis.version', p_version, coalesce(p_local, false));
    PERFORM set_config('tgsis.revision', p_revision::text, coalesce(p_local, false));
    RETURN p_revision;
END
$$;

COMMENT ON FUNCTION tgsis.goto_revision(text, integer, boolean) IS
    'look at revision r of a version''s history (read-only until goto_version); r must be in the version''s working revision set';
