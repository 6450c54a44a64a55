-- tgsis.save_revision(name): freeze the working revision of the session's version under a name; start a new one.
-- The checks come first and take no lock; then the version's row is locked
-- for update, which waits for open writers of the version (they share-lock
-- it) and for another save. Taking the writers' share lock first and then
-- upgrading it would deadlock two saves in one version (each holding the
-- share lock the other's upgrade waits for). The revision frozen is the
-- working revision once the lock is held: a save this one waited for has
-- handed on the one it would have seen before.
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
    SELECT * INTO v_version FROM tgsis.versions WHERE versionid = tgsis.version_id(tgsis.get_working_version());
    PERFORM tgsis.check_writable_revision(v_version.name, v_version.workingrevision);  -- TG301
    PERFORM tgsis.require_version_privilege(v_version.versionid, 'write', 'write in');  -- TG002
    SELECT * INTO v_version FROM tgsis.versions WHERE versionid = v_version.versionid FOR UPDATE;
    IF NOT FOUND THEN
        RAISE EXCEPTION 'version % does not exist', quote_literal(tgsis.get_working_version())
            USING ERRCODE = 'TG200', DETAIL = 'It was deleted while this save_revision waited for it.';
    END IF;
    v_saved := v_version.workingrevision;
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
