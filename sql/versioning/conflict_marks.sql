-- tgsis.conflict_marks(): the stored conflicts whose marks are still their objects' (jsonb), so that a change of storage layout can carry them.
-- A conflict's marks (tgsis.current_conflicts: fingerprints of the changed
-- stored versions, tgsis.changed_objects) depend on how the rows are stored:
-- rows of <table>_ver, or chunk versions of tgsis.<table>_chunk. The storage
-- switch (tgsis.store_in_chunks) changes every mark of a table it switches
-- without changing what any version sees; the next tgsis.find_conflicts would
-- take every solved conflict for one changed again and set it back to
-- unsolved (and drop its stored regions). The switch reads these marks
-- before and gives them to tgsis.renew_conflict_marks after. Each element:
-- [versionid, objectclass, objectkey, childmark, parentmark], only for the
-- conflicts whose stored marks equal the marks of now (a stale one stays as
-- stale). Internal: tgsis's owner, who reads every version's storage.
CREATE FUNCTION tgsis.conflict_marks()
RETURNS jsonb
LANGUAGE sql
STABLE
SET search_path = pg_catalog, pg_temp
AS $$
    SELECT coalesce(pg_catalog.jsonb_agg(pg_catalog.jsonb_build_array(k.versionid, k.objectclass, k.objectkey,
                                                                       k.childmark, k.parentmark)
                                         ORDER BY k.versionid, k.objectclass, k.objectkey), '[]'::jsonb)
      FROM (SELECT DISTINCT c.versionid FROM tgsis.conflicts c) v
     CROSS JOIN LATERAL tgsis.current_conflicts(v.versionid) f
      JOIN tgsis.conflicts k ON k.versionid = v.versionid AND k.objectclass = f.objectclass AND k.objectkey = f.objectkey
     WHERE k.childmark = f.childmark AND k.parentmark = f.parentmark
$$;

REVOKE ALL ON FUNCTION tgsis.conflict_marks() FROM PUBLIC;

COMMENT ON FUNCTION tgsis.conflict_marks() IS
    'the stored conflicts whose marks are still their objects'' (jsonb array of [versionid, objectclass, objectkey, childmark, parentmark]): read before a change of storage layout, given to tgsis.renew_conflict_marks after it';
