-- tgsis.merge_property_rows(table, geoid, since, keys, base, parent, version): a property table's rows for the merge by region.
-- The vertex or cell property rows (_idx = vertex or cell id) of one feature
-- that tgsis.mesh_merge_regions compares, read from the table's storage
-- through tgsis.storage_run (the caller's rights, or the owner's runner as
-- tgsis's owner). Without p_keys: the keys of the rows whose visibility can
-- differ between the three sets (revision or lastrevs in p_since), seen and
-- val NULL. With p_keys: every row of those keys some set sees, seen saying
-- where (bit 1 base, 2 parent, 4 version), val its values as one canonical
-- text: the columns other than _geoid and _idx in order, a float as its
-- exact text with -0 as 0 and NULL as NaN (so that equal texts are equal
-- values as tgsis.merge3 compares them: NaN equals NaN and a missing row),
-- any other value as its text, NULL as NaN. nulls (tgsis.merge_value_text)
-- is the text of a missing row. p_times (model 2): the rows of that instant only (_times), the
-- property tables of a surface at instants being keyed (_times, _idx); with p_timem (model 3) the rows of
-- the geometry instant p_times of the period p_timem (_timem, _timet). extra_float_digits is pinned:
-- exact floats. A property table stored in chunks (tgsis.store_class_in_chunks)
-- is read as its decoded chunk versions (tgsis.storage_row_versions: with
-- p_keys only the chunks holding them).
CREATE FUNCTION tgsis.merge_property_rows(p_t tgsis.versioned_tables, p_geoid bigint, p_since integer[],
                                          p_keys bigint[], p_base integer[], p_parent integer[], p_child integer[],
                                          p_times float8 DEFAULT NULL, p_timem float8 DEFAULT NULL)
RETURNS TABLE (key bigint, seen integer, val text)
LANGUAGE plpgsql
VOLATILE
SET search_path = pg_catalog, pg_temp
SET extra_float_digits = 1
AS $$
DECLARE
    v_canon text := (SELECT m.canon FROM tgsis.merge_value_text(p_t.schemaname, p_t.tablename) AS m);
    v_vis   text := '(v.revision = ANY (%1$s) AND NOT (v.revclosed AND v.lastrevs && %1$s))';
    v_slice text := CASE WHEN p_timem IS NOT NULL THEN format(' AND v._timem = %L::float8 AND v._timet = %L::float8', p_timem, p_times)
                         WHEN p_times IS NOT NULL THEN format(' AND v._times = %L::float8', p_times) ELSE '' END;
BEGIN
    IF v_canon IS NULL THEN
        RETURN;
    END IF;
    IF p_keys IS NULL THEN
        RETURN QUERY
        SELECT r[1]::bigint, NULL::integer, NULL::text
          FROM tgsis.storage_run(p_t, false, format(
                 'SELECT ARRAY[v._idx::text] FROM %s v WHERE v._geoid = $1[1]::bigint
                     AND (v.revision = ANY ($1[2]::integer[]) OR (v.revclosed AND v.lastrevs && $1[2]::integer[]))%s',
                 tgsis.storage_row_versions(p_t.schemaname, p_t.tablename), v_slice),
               p_1 => ARRAY[p_geoid::text, p_since::text]) AS r;
        RETURN;
    END IF;
    RETURN QUERY
    SELECT r[1]::bigint, r[2]::integer, r[3]
      FROM tgsis.storage_run(p_t, false, format(
             'SELECT ARRAY[w._idx::text, w.seen::text, w.val]
                FROM (SELECT v._idx, %1$s::integer | (%2$s::integer << 1) | (%3$s::integer << 2) AS seen, %4$s AS val
                        FROM %5$s v WHERE v._geoid = $1[1]::bigint AND v._idx = ANY ($1[2]::bigint[])%6$s) AS w
               WHERE w.seen <> 0',
             format(v_vis, '$2'), format(v_vis, '$5::integer[]'), format(v_vis, '$3'), v_canon,
             tgsis.storage_row_versions(p_t.schemaname, p_t.tablename, p_keys), v_slice),
           p_1 => ARRAY[p_geoid::text, p_keys::text], p_2 => p_base, p_3 => p_child,
           p_5 => p_parent::bigint[]) AS r;
END
$$;

COMMENT ON FUNCTION tgsis.merge_property_rows(tgsis.versioned_tables, bigint, integer[], bigint[], integer[], integer[], integer[], float8, float8) IS
    'the property rows of one feature for the merge by region in SQL: the keys whose visibility can differ between the three sets (no keys given), or the rows of the keys given with where they are seen (1 base, 2 parent, 4 version) and their values as a canonical text';

-- internal to the merge by region: not executable by PUBLIC; the tgsis roles run it through
-- tgsis.mesh_merge_regions (which a reader may call directly, with its own rights) and the merge's functions
REVOKE ALL ON FUNCTION tgsis.merge_property_rows(tgsis.versioned_tables, bigint, integer[], bigint[], integer[], integer[], integer[], float8, float8) FROM PUBLIC;
GRANT EXECUTE ON FUNCTION tgsis.merge_property_rows(tgsis.versioned_tables, bigint, integer[], bigint[], integer[], integer[], integer[], float8, float8) TO tgsis_reader;
