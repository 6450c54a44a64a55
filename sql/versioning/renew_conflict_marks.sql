-- tgsis.renew_conflict_marks(before): after a change of storage layout, give the conflicts that were current before it the marks of now.
-- p_before is what tgsis.conflict_marks() returned before the change (the
-- storage switch, tgsis.store_in_chunks), in the same transaction: the
-- conflicts still stored with those marks get the marks their objects have
-- now, so that their solutions (and their regions, tgsis.conflict_regions,
-- stored on the same marks) hold, as they would have without the change.
-- Nothing else changes: a conflict that was stale before stays stale, one
-- no longer found is left to tgsis.find_conflicts. Returns the conflicts
-- renewed. Internal: tgsis's owner.
CREATE FUNCTION tgsis.renew_conflict_marks(p_before jsonb)
RETURNS integer
LANGUAGE plpgsql
VOLATILE
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_n integer;
BEGIN
    WITH before AS (
        SELECT (e ->> 0)::integer AS versionid, e ->> 1 AS objectclass, e ->> 2 AS objectkey,
               e ->> 3 AS childmark, e ->> 4 AS parentmark
          FROM jsonb_array_elements(coalesce(p_before, '[]'::jsonb)) AS e),
    marks AS (
        SELECT v.versionid, f.objectclass, f.objectkey, f.childmark, f.parentmark
          FROM (SELECT DISTINCT b.versionid FROM before b) v
         CROSS JOIN LATERAL tgsis.current_conflicts(v.versionid) f),
    renewed AS (
        UPDATE tgsis.conflicts k SET childmark = m.childmark, parentmark = m.parentmark
          FROM before b JOIN marks m USING (versionid, objectclass, objectkey)
         WHERE k.versionid = b.versionid AND k.objectclass = b.objectclass AND k.objectkey = b.objectkey
           AND k.childmark = b.childmark AND k.parentmark = b.parentmark
        RETURNING k.versionid, k.objectclass, k.objectkey, b.childmark AS oldchild, b.parentmark AS oldparent,
                  m.childmark, m.parentmark),
    regions AS (
        UPDATE tgsis.conflict_regions r SET childmark = x.childmark, parentmark = x.parentmark
          FROM renewed x
         WHERE r.versionid = x.versionid AND r.objectclass = x.objectclass AND r.objectkey = x.objectkey
           AND r.childmark = x.oldchild AND r.parentmark = x.oldparent)
    SELECT count(*) INTO v_n FROM renewed;
    RETURN v_n;
END
$$;

REVOKE ALL ON FUNCTION tgsis.renew_conflict_marks(jsonb) FROM PUBLIC;

COMMENT ON FUNCTION tgsis.renew_conflict_marks(jsonb) IS
    'after a change of storage layout (tgsis.store_in_chunks), give the conflicts tgsis.conflict_marks() returned before it (still stored with those marks) the marks of now, in tgsis.conflicts and tgsis.conflict_regions; returns the conflicts renewed';
