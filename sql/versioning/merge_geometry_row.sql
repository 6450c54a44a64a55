-- tgsis.merge_geometry_row(geoid, cell table, set): bring the geometry row's box and counts up to the object's rows in a revision set; rows changed.
-- The last step of the SQL merge by region's write (tgsis.merge_mesh_by_region),
-- as tgsis.db._state_write updates the row after a write of part of the rows:
-- the box and counts of the object's vertex and cell rows in p_set, the
-- session's working set (one pass over each: the rows its views show),
-- written through the view tgsis.geometry only
-- when they differ (0 when equal). The stored box is compared by its 2m
-- coordinates as stored (cube_coord; float8[]'s equality, NaN equal to NaN):
-- cube_ll_coord / cube_ur_coord take the least and greatest of a corner pair
-- by < and >, which hides a NaN, so a box (NaN, 0, 0),(1, 1, 1) read as the
-- measured (1, 0, 0),(1, 1, 1) and was left stale (tests/test_chunk_review5.py).
-- cube's functions are named by the schema
-- the extension is in. A table stored in chunks (tgsis.stored_in_chunks) is
-- read from its chunk versions in p_set, as tgsis.static_extent reads them:
-- the cells counted from each chunk's array length less its holes, the
-- vertices and the box from the unnested coordinate arrays (a hole's NULL is
-- skipped by count and min/max), no slot decoded with its id (through the
-- decoded view every vertex and cell of the object was: 0.55 s of a merge at
-- 90,000 vertices, docs/performance.md). Same visibility test, same values.
-- The chunk table is named by the chunk layer (tgsis.chunk_relation, above
-- this one: named at run time, tests/test_sql_layers.py).
CREATE FUNCTION tgsis.merge_geometry_row(p_geoid bigint, p_table text, p_set integer[])
RETURNS bigint
LANGUAGE plpgsql
VOLATILE
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_n       bigint;
    v_m       bigint;
    v_low     float8[];
    v_high    float8[];
    v_cube    name;
    v_changed bigint;
    v_chunk   text;
BEGIN
    IF tgsis.stored_in_chunks('tgsis', 'vrtx') THEN
        EXECUTE format('SELECT tgsis.%I($1, $2)', 'chunk_relation') INTO v_chunk USING 'vrtx', '_chunk';
        EXECUTE format('SELECT count(u.x), ARRAY[min(u.x), min(u.y), min(u.z)], ARRAY[max(u.x), max(u.y), max(u.z)]
                          FROM %s c CROSS JOIN LATERAL unnest(c.x, c.y, c.z) AS u (x, y, z)
                         WHERE c.geoid = $1 AND c.revision = ANY ($2) AND NOT (c.lastrevs && $2)', v_chunk)
           INTO v_n, v_low, v_high USING p_geoid, p_set;
    ELSE
        EXECUTE format('SELECT count(*), ARRAY[min(v.x), min(v.y), min(v.z)], ARRAY[max(v.x), max(v.y), max(v.z)]
                          FROM %s v WHERE v.geoid = $1 AND v.revision = ANY ($2) AND NOT (v.lastrevs && $2)',
                       tgsis.storage_row_versions('tgsis', 'vrtx'))
           INTO v_n, v_low, v_high USING p_geoid, p_set;
    END IF;
    IF tgsis.stored_in_chunks('tgsis', p_table) THEN
        EXECUTE format('SELECT tgsis.%I($1, $2)', 'chunk_relation') INTO v_chunk USING p_table, '_chunk';
        EXECUTE format('SELECT coalesce(sum(coalesce(cardinality(c.vrtxid1), cardinality(c.vrtxid1_wide))
                                            - coalesce(cardinality(c.holes), 0)), 0)::bigint
                          FROM %s c WHERE c.geoid = $1 AND c.revision = ANY ($2) AND NOT (c.lastrevs && $2)', v_chunk)
           INTO v_m USING p_geoid, p_set;
    ELSE
        EXECUTE format('SELECT count(*) FROM %s v WHERE v.geoid = $1 AND v.revision = ANY ($2) AND NOT (v.lastrevs && $2)',
                       tgsis.storage_row_versions('tgsis', p_table))
           INTO v_m USING p_geoid, p_set;
    END IF;
    IF v_n = 0 THEN
        v_low := NULL;
        v_high := NULL;
    END IF;
    SELECT n.nspname INTO v_cube FROM pg_catalog.pg_extension e JOIN pg_catalog.pg_namespace n ON n.oid = e.extnamespace
     WHERE e.extname = 'cube';
    EXECUTE format('UPDATE tgsis.geometry SET bbox = %1$I.cube($1, $2), nvrtx = $3, ncell = $4
                     WHERE geoid = $5
                       AND ((bbox IS NULL) <> ($1 IS NULL)
                            OR (bbox IS NOT NULL
                                AND ARRAY(SELECT %1$I.cube_coord(bbox, d)
                                            FROM generate_series(1, 2 * %1$I.cube_dim(bbox)) AS d ORDER BY d)
                                    IS DISTINCT FROM $1 || $2)
                            OR nvrtx <> $3 OR ncell <> $4)', v_cube)
      USING v_low, v_high, v_n, v_m, p_geoid;
    GET DIAGNOSTICS v_changed = ROW_COUNT;
    RETURN v_changed;
END
$$;

COMMENT ON FUNCTION tgsis.merge_geometry_row(bigint, text, integer[]) IS
    'bring a feature''s geometry row (box, vertex and cell counts) up to its rows in a revision set (the session''s working set), through the view, when they differ; returns the rows changed (0 or 1)';

-- internal to the psql merge by region (reached only through the SECURITY DEFINER merge, find_conflicts and
-- resolve functions): not executable by PUBLIC, like tgsis's other internal helpers
REVOKE ALL ON FUNCTION tgsis.merge_geometry_row(bigint, text, integer[]) FROM PUBLIC;
