-- tgsis.save_revision(name): freeze the working revision of the session's version under a name; start a new one.
CREATE FUNCTION tgsis.save_revision(p_name text)
RETURNS integer
LANGUAGE plpgsql
VOLATILE
SECURITY DEFINER
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_version tgsis.versions;
    v_saved   integer;
BEGIN
    PERFORM tgsis.check_version_name(p_name, 'revision');
    v_saved := (tgsis.write_revision()).revision;  -- TG301 while an older revision is viewed
    SELECT * INTO v_version FROM tgsis.versions WHERE name = tgsis.get_working_version() FOR UPDATE;
    IF EXISTS (SELECT FROM tgsis.revisions WHERE versionid = v_version.versionid AND name = p_name) THEN
        RAISE EXCEPTION 'version % has a revision named % already', quote_literal(v_version.name), quote_literal(p_name)
            USING ERRCODE = 'TG201';
    END IF;
    UPDATE tgsis.revisions SET name = p_name, saved_at = now() WHERE revision = v_saved;
    PERFORM tgsis.next_working_revision(v_version.versionid);
    RETURN v_saved;
END
$$;

COMMENT ON FUNCTION tgsis.save_revision(text) IS
    'freeze the working revision of the session''s version under a name (it can be viewed, never changed) and give the version a new working revision; returns the frozen revision';
