-- tgsis.lock_objects(version, objectclass, keys, exclusive): lock objects for a version so that no other version can change them; returns the locks taken.
-- Needs the write right on the version; the objects must exist in it.
-- Taking a lock the version holds already changes nothing (or makes it
-- exclusive for the caller); a lock held elsewhere fails with TG303. Keys
-- are read in the key column's type with the session's settings and locked
-- by their canonical text (tgsis.canonical_object_keys), the text every
-- writer of the object names it by.
CREATE FUNCTION tgsis.lock_objects(p_version text, p_objectclass text, p_keys text[], p_exclusive boolean DEFAULT false)
RETURNS integer
LANGUAGE plpgsql
VOLATILE
SECURITY DEFINER
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_id      integer := tgsis.version_id(p_version);
    v_role    name := tgsis.calling_role();
    v_missing text[];
    v_none    text[];
    v_taken   integer;
BEGIN
    PERFORM tgsis.require_version_privilege(v_id, 'write', 'lock objects in');
    PERFORM tgsis.check_object_class(p_objectclass);
    IF p_keys IS NULL OR cardinality(p_keys) = 0 OR array_position(p_keys, NULL) IS NOT NULL THEN
        RAISE EXCEPTION 'no object keys to lock' USING ERRCODE = 'TG100', HINT = 'pass a non-empty array of keys without NULLs';
    END IF;
    p_keys := tgsis.canonical_object_keys(p_objectclass, p_keys);
    SELECT array_agg(k ORDER BY k) INTO v_missing
      FROM unnest(p_keys) AS k
     WHERE k <> ALL (tgsis.visible_object_keys(p_objectclass, p_keys,
                                               (SELECT workingset FROM tgsis.versions WHERE versionid = v_id)));
    -- features of classes without versioning are written in DEFAULT only: a lock of another version would
    -- only keep DEFAULT from writing them
    IF p_objectclass = 'feature' AND v_id <> 0 THEN
        SELECT array_agg(u.geoid::text ORDER BY u.geoid) INTO v_none
          FROM tgsis.unversioned_features u
         WHERE u.geoid = ANY (ARRAY(SELECT k::bigint FROM unnest(p_keys) AS k WHERE k ~ '^-?[0-9]{1,18}$'));
        IF v_none IS NOT NULL THEN
            RAISE EXCEPTION 'features % are of classes without versioning: version % cannot lock them',
                    array_to_string(v_none, ', '), quote_literal(p_version)
                USING ERRCODE = 'TG305',
                      DETAIL = 'They hold one state, which every version sees and only DEFAULT writes.',
                      HINT = 'lock them in DEFAULT, or leave them out';
        END IF;
    END IF;
    IF v_missing IS NOT NULL THEN
        RAISE EXCEPTION 'version % has no object % of class %', quote_literal(p_version), array_to_string(v_missing, ', '),
                quote_literal(p_objectclass)
            USING ERRCODE = 'TG200';
    END IF;

    INSERT INTO tgsis.object_locks (objectclass, objectkey, versionid, exclusive, locked_by)
    SELECT DISTINCT p_objectclass, k, v_id, coalesce(p_exclusive, false), v_role FROM unnest(p_keys) AS k
        ON CONFLICT DO NOTHING;
    GET DIAGNOSTICS v_taken = ROW_COUNT;
    -- locks the version held already: the caller may make its own exclusive
    UPDATE tgsis.object_locks SET exclusive = true, locked_by = v_role, locked_at = now()
     WHERE objectclass = p_objectclass AND objectkey = ANY (p_keys) AND versionid = v_id
       AND coalesce(p_exclusive, false) AND NOT exclusive;
    -- whatever is held elsewhere (or exclusively by another role) now fails the whole call
    PERFORM tgsis.check_objects_unlocked(p_objectclass, p_keys, v_id);
    RETURN v_taken;
END
$$;

COMMENT ON FUNCTION tgsis.lock_objects(text, text, text[], boolean) IS
    'lock objects of a class for a version (write right needed): other versions, and with p_exclusive other roles, cannot change them (TG303) until tgsis.unlock_objects; returns the number of new locks';
