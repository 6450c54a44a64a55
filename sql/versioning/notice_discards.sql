-- tgsis.notice_discards(version, doing, objectclass, objectkey): a NOTICE per conflict whose recorded solution discards edits.
-- So that psql users are told, when they record a solution and when a merge
-- or refresh applies it, what of the other side's edits is thrown away
-- (tgsis.conflict_discards; 'manual' keeps the version's object, so it loses
-- what 'child' loses). Reads the solutions as tgsis.conflicts holds them now:
-- call it after they are recorded (resolve) or recomputed (merge, refresh).
-- Returns the number of objects it told about.
CREATE FUNCTION tgsis.notice_discards(p_version text, p_doing text, p_objectclass text DEFAULT NULL,
                                      p_objectkey text DEFAULT NULL)
RETURNS integer
LANGUAGE plpgsql
VOLATILE
AS $$
DECLARE
    v_id    integer := tgsis.version_id(p_version);
    v_obj   record;
    v_count integer := 0;
BEGIN
    IF NOT EXISTS (SELECT FROM tgsis.conflicts k WHERE k.versionid = v_id AND k.solution IN ('child', 'parent', 'manual')
                      AND (p_objectclass IS NULL OR k.objectclass = p_objectclass)
                      AND (p_objectkey IS NULL OR k.objectkey = p_objectkey)) THEN
        RETURN 0;
    END IF;
    FOR v_obj IN
        SELECT d.objectclass, d.objectkey, k.solution, d.discarded,
               string_agg(format('%s: %s', d.shortname,
                                 concat_ws(', ', CASE WHEN d.rows_added > 0 THEN d.rows_added || ' added' END,
                                           CASE WHEN d.rows_removed > 0 THEN d.rows_removed || ' removed' END,
                                           CASE WHEN d.rows_changed > 0 THEN d.rows_changed || ' changed' END))
                          || format(' (%s value%s)', d.values_changed, CASE WHEN d.values_changed <> 1 THEN 's' END),
                          '; ' ORDER BY d.shortname) AS said
          FROM tgsis.conflict_discards(p_version, p_objectclass, p_objectkey) AS d
          JOIN tgsis.conflicts k ON k.versionid = v_id AND k.objectclass = d.objectclass AND k.objectkey = d.objectkey
         WHERE d.solution = CASE k.solution WHEN 'parent' THEN 'parent' WHEN 'unsolved' THEN NULL ELSE 'child' END
         GROUP BY 1, 2, 3, 4
         ORDER BY 1, 2
    LOOP
        RAISE NOTICE '% % of version % (solution %) %: % edits discarded: %', v_obj.objectclass, v_obj.objectkey,
            quote_literal(p_version), v_obj.solution, p_doing,
            CASE v_obj.discarded WHEN 'parent' THEN 'the parent''s' ELSE 'the version''s' END, v_obj.said;
        v_count := v_count + 1;
    END LOOP;
    RETURN v_count;
END
$$;

COMMENT ON FUNCTION tgsis.notice_discards(text, text, text, text) IS
    'raise a NOTICE per conflict of a version (optionally one class or object) whose recorded solution discards the other side''s edits, with the counts of tgsis.conflict_discards; returns how many';

-- internal to the merges: reached only through the SECURITY DEFINER merge, refresh and resolve functions, as
-- their owner; not executable by PUBLIC (tests/test_function_grants.py)
REVOKE ALL ON FUNCTION tgsis.notice_discards(text, text, text, text) FROM PUBLIC;
