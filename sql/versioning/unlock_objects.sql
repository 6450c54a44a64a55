-- tgsis.unlock_objects(version, objectclass, keys): release a version's locks (all of them, of a class, or of some keys); returns the locks released.
-- Needs the write right on the version; another role's exclusive lock only
-- its owner or a tgsis_admin may release. With a class, keys are read as
-- tgsis.lock_objects reads them (tgsis.canonical_object_keys).
CREATE FUNCTION tgsis.unlock_objects(p_version text, p_objectclass text DEFAULT NULL, p_keys text[] DEFAULT NULL)
RETURNS integer
LANGUAGE plpgsql
VOLATILE
SECURITY DEFINER
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_id       integer := tgsis.version_id(p_version);
    v_role     name := tgsis.calling_role();
    v_others   text;
    v_released integer;
BEGIN
    PERFORM tgsis.require_version_privilege(v_id, 'write', 'unlock objects in');
    IF p_objectclass IS NOT NULL THEN
        PERFORM tgsis.check_object_class(p_objectclass);
        p_keys := tgsis.canonical_object_keys(p_objectclass, p_keys);
    END IF;
    IF NOT tgsis.is_version_owner(v_id, v_role) THEN
        SELECT string_agg(format('%s %s (%s)', objectclass, objectkey, quote_ident(locked_by)), ', ') INTO v_others
          FROM tgsis.object_locks
         WHERE versionid = v_id AND (p_objectclass IS NULL OR objectclass = p_objectclass)
           AND (p_keys IS NULL OR objectkey = ANY (p_keys)) AND exclusive AND locked_by <> v_role;
        IF v_others IS NOT NULL THEN
            RAISE EXCEPTION 'role % may not release exclusive locks of other roles: %', quote_ident(v_role), v_others
                USING ERRCODE = 'TG002', HINT = 'the version''s owner or a tgsis_admin may';
        END IF;
    END IF;
    DELETE FROM tgsis.object_locks
     WHERE versionid = v_id AND (p_objectclass IS NULL OR objectclass = p_objectclass)
       AND (p_keys IS NULL OR objectkey = ANY (p_keys));
    GET DIAGNOSTICS v_released = ROW_COUNT;
    RETURN v_released;
END
$$;

COMMENT ON FUNCTION tgsis.unlock_objects(text, text, text[]) IS
    'release object locks a version holds (all, those of a class, or of some keys); returns how many; another role''s exclusive lock needs the version''s owner or a tgsis_admin';
