-- tgsis.check_no_unsolved_conflicts(version, action): recompute a version's conflicts; TG302 naming the unsolved ones.
-- The unsolved regions of a surface at instants (an evolving surface) are named with their instant (geometry instant and
-- period), as the Python merge names them: extra_float_digits is pinned (an instant such as 0.1 + 0.2 is named
-- 0.30000000000000004, not 0.3, whatever the session's setting). Python's repr is positional below 1e16 where the
-- float8 text is not (from 1e15 on): such an instant goes through numeric from its exact text (a float8::numeric cast
-- keeps 15 digits: 2500000000000002.0 was named 2500000000000000.0; -0.0 is named 0.0, as the merge's keys are).
-- Its hint points meshes whose regions are stored (tgsis.conflict_regions) to the Python merge by
-- region (tgsis version merge / refresh), which also applies average and manual solutions (the SQL
-- merge by region, tgsis.merge_regions_in_sql, merges the others once their regions are solved).
CREATE FUNCTION tgsis.check_no_unsolved_conflicts(p_version text, p_action text)
RETURNS void
LANGUAGE plpgsql
VOLATILE
SET extra_float_digits = 1
AS $$
DECLARE
    v_count integer;
    v_list  text;
    v_regions text;
    v_slices  text;
BEGIN
    SELECT count(*), string_agg(format('%s %s (%s)', objectclass, objectkey,
                                       coalesce(nullif(array_to_string(conflicttype, ', '), ''), 'different tables')),
                                '; ' ORDER BY objectclass, objectkey)
      INTO v_count, v_list
      FROM tgsis.find_conflicts(p_version) WHERE solution = 'unsolved';
    IF v_count > 0 THEN
        -- the unsolved meshes whose regions are stored (current marks: find_conflicts dropped older ones)
        -- merge by region once solved (average and manual solutions need the Python client: numpy)
        SELECT string_agg(DISTINCT format('%s %s', r.objectclass, r.objectkey), ', ')
          INTO v_regions
          FROM tgsis.conflict_regions r JOIN tgsis.conflicts k USING (versionid, objectclass, objectkey)
         WHERE r.versionid = tgsis.version_id(p_version) AND k.solution = 'unsolved';
        -- the unsolved regions of the instants of surfaces at instants, named as the Python merge names them
        -- (`region 3 at instant 2.0 unsolved`)
        SELECT string_agg(format('%s %s: region %s at %s unsolved', r.objectclass, r.objectkey, r.region,
                                 CASE WHEN r.timem IS NULL THEN 'instant ' ELSE 'geometry instant ' END
                                 || CASE WHEN abs(r.times) < 1e16 AND (r.times = trunc(r.times) OR abs(r.times) >= 1e15)
                                         THEN r.times::text::numeric::text || CASE WHEN r.times = trunc(r.times) THEN '.0' ELSE '' END
                                         ELSE r.times::text END
                                 || CASE WHEN r.timem IS NULL THEN ''
                                         ELSE ' of the period starting at '
                                              || CASE WHEN abs(r.timem) < 1e16 AND (r.timem = trunc(r.timem) OR abs(r.timem) >= 1e15)
                                                      THEN r.timem::text::numeric::text
                                                           || CASE WHEN r.timem = trunc(r.timem) THEN '.0' ELSE '' END
                                                      ELSE r.timem::text END END),
                          '; ' ORDER BY r.objectclass, r.objectkey, r.region)
          INTO v_slices
          FROM tgsis.conflict_regions r JOIN tgsis.conflicts k USING (versionid, objectclass, objectkey)
         WHERE r.versionid = tgsis.version_id(p_version) AND k.solution = 'unsolved' AND r.solution = 'unsolved'
           AND r.times IS NOT NULL;
        RAISE EXCEPTION '% of version % refused: % unsolved conflict(s): %', p_action, quote_literal(p_version), v_count,
                v_list || coalesce('; ' || v_slices, '')
            USING ERRCODE = 'TG302',
                  HINT = CASE WHEN v_regions IS NULL
                              THEN format('record a solution for each: SELECT tgsis.resolve_conflict(%L, class, key, ''parent''|''child''|''manual'')',
                                          p_version)
                              ELSE format('the meshes %s merge by region: `tgsis version %s %s` or tgsis.%s_version(conn, %s) in Python merges them '
                                          '(solve their conflicting regions first: SELECT tgsis.resolve_region(%L, class, key, region, ''parent''|''child''|''base'')); '
                                          'record a solution for the others: SELECT tgsis.resolve_conflict(%L, class, key, ''parent''|''child''|''manual'')',
                                          v_regions, p_action, tgsis.shell_quote(p_version), p_action,
                                          pg_catalog.to_json(p_version)::text, p_version, p_version) END;
    END IF;
END
$$;

COMMENT ON FUNCTION tgsis.check_no_unsolved_conflicts(text, text) IS
    'recompute the conflicts of a version and raise TG302 naming the unsolved ones (before a merge or refresh)';

-- internal to the merges: reached only through the SECURITY DEFINER merge, refresh, find_conflicts and
-- resolve functions, as their owner; not executable by PUBLIC (tests/test_function_grants.py)
REVOKE ALL ON FUNCTION tgsis.check_no_unsolved_conflicts(text, text) FROM PUBLIC;
