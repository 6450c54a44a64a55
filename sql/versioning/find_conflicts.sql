-- tgsis.find_conflicts(version): (re)compute the conflicting objects of a version against its parent.
-- An object conflicts when, since the version's initrevision, it was changed
-- both in the version and in the parent. Solutions recorded earlier are kept
-- while neither side changed the object again; conflicts that are gone are
-- removed.
CREATE FUNCTION tgsis.find_conflicts(p_version text)
RETURNS SETOF tgsis.conflicts
LANGUAGE plpgsql
VOLATILE
SECURITY DEFINER
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_version tgsis.versions;
    v_parent  integer[];
BEGIN
    SELECT * INTO v_version FROM tgsis.versions WHERE versionid = tgsis.version_id(p_version);
    IF v_version.parentid IS NULL THEN
        RAISE EXCEPTION 'version DEFAULT has no parent to conflict with' USING ERRCODE = 'TG100';
    END IF;
    SELECT coalesce(array_agg(revision), '{}') INTO v_parent
      FROM tgsis.revisions WHERE versionid = v_version.parentid AND revision > v_version.initrevision;

    WITH changes AS (
        SELECT side, objectclass, objectkey, array_agg(shortname ORDER BY shortname) AS tables,
               md5(string_agg(shortname || ':' || mark, ',' ORDER BY shortname)) AS mark
          FROM (SELECT 'child' AS side, * FROM tgsis.changed_objects(tgsis.own_working_revisions(v_version.versionid))
                UNION ALL
                SELECT 'parent', * FROM tgsis.changed_objects(v_parent)) AS c
         GROUP BY 1, 2, 3),
    found AS (
        SELECT c.objectclass, c.objectkey,
               ARRAY(SELECT unnest(c.tables) INTERSECT SELECT unnest(p.tables) ORDER BY 1) AS conflicttype,
               c.tables AS childtables, p.tables AS parenttables, c.mark AS childmark, p.mark AS parentmark
          FROM changes c JOIN changes p USING (objectclass, objectkey)
         WHERE c.side = 'child' AND p.side = 'parent'),
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
    RETURN QUERY SELECT * FROM tgsis.conflicts WHERE versionid = v_version.versionid ORDER BY objectclass, objectkey;
END
$$;

COMMENT ON FUNCTION tgsis.find_conflicts(text) IS
    '(re)compute and return the objects changed both in a version and in its parent since the version was based; keeps solutions while neither side changed the object again';
