-- tgsis.find_conflicts(version): (re)compute the conflicting objects of a version against its parent.
-- An object conflicts when, since the version's initrevision, it was changed
-- both in the version and in the parent (tgsis.current_conflicts). Solutions
-- recorded earlier are kept while neither side changed the object again;
-- conflicts that are gone are removed. Only a role that may write in the
-- version or merge into its parent stores the result (which locks the
-- version's conflict rows until its transaction ends): anyone else who may
-- read gets the same answer computed, without writing or locking anything.
-- Storing also removes the regions of meshes (tgsis.conflict_regions) found on
-- marks that are no longer the object's: they describe a state that is gone,
-- and finds, in SQL, those of the unsolved meshes without regions
-- (tgsis.store_mesh_regions) unless the client finds them itself.
CREATE FUNCTION tgsis.find_conflicts(p_version text)
RETURNS SETOF tgsis.conflicts
LANGUAGE plpgsql
VOLATILE
SECURITY DEFINER
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_version tgsis.versions;
    v_role    name := tgsis.calling_role();
    v_key     text;
BEGIN
    SELECT * INTO v_version FROM tgsis.versions WHERE versionid = tgsis.version_id(p_version);
    IF v_version.parentid IS NULL THEN
        RAISE EXCEPTION 'version DEFAULT has no parent to conflict with' USING ERRCODE = 'TG100';
    END IF;
    IF NOT (tgsis.holds_version_privilege(v_version.versionid, 'write', v_role)
            OR tgsis.holds_version_privilege(v_version.parentid, 'merge', v_role)) THEN
        RETURN QUERY
            SELECT v_version.versionid, f.objectclass, f.objectkey, f.conflicttype, f.childtables, f.parenttables,
                   f.childmark, f.parentmark,
                   CASE WHEN (k.childmark, k.parentmark) = (f.childmark, f.parentmark) THEN k.solution ELSE 'unsolved' END,
                   coalesce(k.detected_at, now()),
                   CASE WHEN (k.childmark, k.parentmark) = (f.childmark, f.parentmark) THEN k.solved_at END,
                   CASE WHEN (k.childmark, k.parentmark) = (f.childmark, f.parentmark) THEN k.solved_by END
              FROM tgsis.current_conflicts(v_version.versionid) AS f
              LEFT JOIN tgsis.conflicts k ON k.versionid = v_version.versionid AND k.objectclass = f.objectclass
                                         AND k.objectkey = f.objectkey
             ORDER BY f.objectclass, f.objectkey;
        RETURN;
    END IF;

    WITH found AS (SELECT * FROM tgsis.current_conflicts(v_version.versionid)),
    gone AS (
        DELETE FROM tgsis.conflicts k
         WHERE k.versionid = v_version.versionid
           AND NOT EXISTS (SELECT FROM found f WHERE f.objectclass = k.objectclass AND f.objectkey = k.objectkey))
    INSERT INTO tgsis.conflicts AS k (versionid, objectclass, objectkey, conflicttype, childtables, parenttables,
                                      childmark, parentmark)
    SELECT v_version.versionid, f.* FROM found f
        ON CONFLICT (versionid, objectclass, objectkey) DO UPDATE
       SET conflicttype = excluded.conflicttype, childtables = excluded.childtables,
           parenttables = excluded.parenttables, childmark = excluded.childmark, parentmark = excluded.parentmark,
           -- a solution holds for the state it was given on
           solution = CASE WHEN (k.childmark, k.parentmark) = (excluded.childmark, excluded.parentmark)
                           THEN k.solution ELSE 'unsolved' END,
           solved_at = CASE WHEN (k.childmark, k.parentmark) = (excluded.childmark, excluded.parentmark)
                            THEN k.solved_at END,
           solved_by = CASE WHEN (k.childmark, k.parentmark) = (excluded.childmark, excluded.parentmark)
                            THEN k.solved_by END;
    -- regions of a mesh hold for the marks they were found on (tgsis.conflict_regions): a side that
    -- changed the object since makes them stale; gone conflicts took theirs along (ON DELETE CASCADE)
    DELETE FROM tgsis.conflict_regions r
     USING tgsis.conflicts k
     WHERE r.versionid = v_version.versionid AND k.versionid = r.versionid AND k.objectclass = r.objectclass
       AND k.objectkey = r.objectkey AND (k.childmark, k.parentmark) IS DISTINCT FROM (r.childmark, r.parentmark);
    -- the regions of the unsolved meshes that have none stored on their marks, found in SQL
    -- (tgsis.store_mesh_regions: what tgsis.merge3 finds), so that a psql user has them too. A client
    -- that finds them itself in this transaction (tgsis.find_conflicts and the merges by region in
    -- Python) says so (tgsis.region_detection = 'client'), and they are not computed twice.
    IF current_setting('tgsis.region_detection', true) IS DISTINCT FROM 'client' THEN
        FOR v_key IN
            SELECT k.objectkey FROM tgsis.conflicts k
             WHERE k.versionid = v_version.versionid AND k.objectclass = 'feature' AND k.solution = 'unsolved'
               AND NOT EXISTS (SELECT FROM tgsis.conflict_regions r WHERE r.versionid = k.versionid
                                  AND r.objectclass = k.objectclass AND r.objectkey = k.objectkey)
             ORDER BY k.objectkey::bigint
        LOOP
            PERFORM tgsis.store_mesh_regions(p_version, v_key);
        END LOOP;
    END IF;
    RETURN QUERY SELECT * FROM tgsis.conflicts WHERE versionid = v_version.versionid ORDER BY objectclass, objectkey;
END
$$;

COMMENT ON FUNCTION tgsis.find_conflicts(text) IS
    '(re)compute and return the objects changed both in a version and in its parent since the version was based; keeps solutions while neither side changed the object again, and removes the stored regions of objects that changed since they were found; stored only for roles that may write in the version or merge into its parent';
