-- tgsis.merge_instant_rows(table, geoid, key columns, columns, base, parent set, version set): an object's per-instant feature property rows in the three states, merged column by column.
-- The per-instant feature properties (<class>_pros) of the psql merges of
-- temporal surfaces (tgsis.merge_instants_by_slice, keyed _times;
-- tgsis.merge_periods_by_slice, keyed _timem, _timet), as
-- tgsis._merge_slices._merge_rows merges them: per key (the values of
-- p_keys) the row of the columns p_cols as text in the base, the parent and
-- the version (NULL: none), the merged row (tgsis.merge_instant_values) and
-- whether it is an object-level conflict; keys ascending. Read from the
-- storage at the three revision sets through tgsis.storage_run.
CREATE FUNCTION tgsis.merge_instant_rows(p_table tgsis.versioned_tables, p_geoid bigint, p_keys text[], p_cols text[],
                                         p_base integer[], p_parentset integer[], p_versionset integer[])
RETURNS TABLE (key float8[], base text[], parent text[], version text[], merged text[], conflict boolean)
LANGUAGE plpgsql
VOLATILE
SET search_path = pg_catalog, pg_temp
SET extra_float_digits = 1
AS $$
DECLARE
    v_k integer := cardinality(p_keys);
BEGIN
    RETURN QUERY
    WITH r AS (
        SELECT x[1]::smallint AS st, x[2:v_k + 1]::float8[] AS k, x[v_k + 2:] AS vals
          FROM tgsis.storage_run(p_table, false, format(
                 'SELECT ARRAY[s.st::text, %s] || ARRAY[%s]
                    FROM %I.%I v, (VALUES (1, $2), (2, $3), (4, $1[2]::integer[])) AS s (st, revs)
                   WHERE v._geoid = $1[1]::bigint AND v.revision = ANY (s.revs) AND NOT (v.revclosed AND v.lastrevs && s.revs)',
                 (SELECT string_agg(format('v.%I::text', c), ', ' ORDER BY o) FROM unnest(p_keys) WITH ORDINALITY AS u(c, o)),
                 (SELECT string_agg(format('v.%I::text', c), ', ' ORDER BY o) FROM unnest(p_cols) WITH ORDINALITY AS u(c, o)),
                 p_table.schemaname, p_table.tablename || '_ver'),
               p_1 => ARRAY[p_geoid::text, p_versionset::text], p_2 => p_base, p_3 => p_parentset) AS x)
    SELECT k.k, b.vals, p.vals, c.vals, m.p_merged, m.p_conflict
      FROM (SELECT DISTINCT r.k FROM r) AS k
      LEFT JOIN r b ON b.st = 1 AND b.k = k.k
      LEFT JOIN r p ON p.st = 2 AND p.k = k.k
      LEFT JOIN r c ON c.st = 4 AND c.k = k.k
      CROSS JOIN LATERAL tgsis.merge_instant_values(b.vals, p.vals, c.vals) AS m
     ORDER BY k.k;
END
$$;

-- internal to the psql merges, not executable by PUBLIC (tests/test_function_grants.py)
REVOKE ALL ON FUNCTION tgsis.merge_instant_rows(tgsis.versioned_tables, bigint, text[], text[], integer[], integer[], integer[]) FROM PUBLIC;

COMMENT ON FUNCTION tgsis.merge_instant_rows(tgsis.versioned_tables, bigint, text[], text[], integer[], integer[], integer[]) IS
    'an object''s per-instant feature property rows (values as text) in the base, the parent and the version, per key, merged column by column as the Python merge merges them, with whether the merge is an object-level conflict';
