-- tgsis.current_conflicts(versionid): the objects changed both in a version and in its parent since its base, as they stand now.
-- An object conflicts when, since the version's initrevision, it was changed
-- both in the version and in the parent. The marks fingerprint each side's
-- changes, so that a solution recorded for one state can be told from a
-- later one. Computed, not stored: tgsis.find_conflicts stores it.
CREATE FUNCTION tgsis.current_conflicts(p_versionid integer)
RETURNS TABLE (objectclass text, objectkey text, conflicttype text[], childtables text[], parenttables text[],
               childmark text, parentmark text)
LANGUAGE sql
STABLE
AS $$
    WITH version AS (
        SELECT v.versionid, v.parentid, v.initrevision FROM tgsis.versions v WHERE v.versionid = p_versionid),
    parent_revisions AS (
        SELECT coalesce(array_agg(r.revision), '{}') AS revs
          FROM tgsis.revisions r, version v WHERE r.versionid = v.parentid AND r.revision > v.initrevision),
    changes AS (
        SELECT c.side, c.objectclass, c.objectkey, array_agg(c.shortname ORDER BY c.shortname) AS tables,
               md5(string_agg(c.shortname || ':' || c.mark, ',' ORDER BY c.shortname)) AS mark
          FROM (SELECT 'child' AS side, o.* FROM tgsis.changed_objects(tgsis.own_working_revisions(p_versionid)) AS o
                UNION ALL
                SELECT 'parent', o.* FROM parent_revisions p, tgsis.changed_objects(p.revs) AS o) AS c
         GROUP BY 1, 2, 3)
    SELECT c.objectclass, c.objectkey,
           ARRAY(SELECT unnest(c.tables) INTERSECT SELECT unnest(p.tables) ORDER BY 1),
           c.tables, p.tables, c.mark, p.mark
      FROM changes c JOIN changes p USING (objectclass, objectkey)
     WHERE c.side = 'child' AND p.side = 'parent'
$$;

COMMENT ON FUNCTION tgsis.current_conflicts(integer) IS
    'objects of a version changed on both sides since its base, with the tables each side changed and fingerprints of the changes; computed now, not stored (tgsis.find_conflicts stores them)';

-- internal to the merges, not executable by PUBLIC (tests/test_function_grants.py); the Python merge and the browser view ask it as the calling tgsis role
REVOKE ALL ON FUNCTION tgsis.current_conflicts(integer) FROM PUBLIC;
GRANT EXECUTE ON FUNCTION tgsis.current_conflicts(integer) TO tgsis_reader;
