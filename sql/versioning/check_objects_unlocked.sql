-- tgsis.check_objects_unlocked(objectclass, keys, versionid, by_role): TG303 when another version (or role) holds a lock on one of the objects.
-- p_versionid is the version that writes (default: the session's working
-- version); with p_by_role an exclusive lock of that version also stops
-- other roles (a merge writes for the version, not for a role: it passes false).
CREATE FUNCTION tgsis.check_objects_unlocked(p_objectclass text, p_keys text[], p_versionid integer DEFAULT NULL,
                                             p_by_role boolean DEFAULT true)
RETURNS void
LANGUAGE plpgsql
STABLE
SECURITY DEFINER
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_writer integer := coalesce(p_versionid, tgsis.version_id(tgsis.get_working_version()));
    v_role   name := tgsis.calling_role();
    v_held   text;
    v_count  integer;
BEGIN
    SELECT string_agg(format('%s (locked by version %L, %s%s)', l.objectkey, v.name, quote_ident(l.locked_by),
                             CASE WHEN l.exclusive THEN ', exclusive' ELSE '' END), '; ' ORDER BY l.objectkey),
           count(*)
      INTO v_held, v_count
      FROM tgsis.object_locks l JOIN tgsis.versions v ON v.versionid = l.versionid
     WHERE l.objectclass = p_objectclass AND l.objectkey = ANY (p_keys)
       AND (l.versionid <> v_writer OR (p_by_role AND l.exclusive AND l.locked_by <> v_role));
    IF v_count > 0 THEN
        RAISE EXCEPTION '% of class % locked by another version or role: %',
                CASE WHEN v_count = 1 THEN 'object' ELSE v_count || ' objects' END, quote_literal(p_objectclass), v_held
            USING ERRCODE = 'TG303',
                  DETAIL = format('Writes from version %L cannot change them while the lock is held.',
                                  (SELECT name FROM tgsis.versions WHERE versionid = v_writer)),
                  HINT = 'the holder releases them with SELECT tgsis.unlock_objects(version, objectclass, keys); SELECT * FROM tgsis.object_locks lists locks';
    END IF;
END
$$;

COMMENT ON FUNCTION tgsis.check_objects_unlocked(text, text[], integer, boolean) IS
    'raise TG303 naming the objects (and holders) when objects of a class are locked by a version other than the writing one, or exclusively by another role';
