-- tgsis.gmap_alpha_array(geoid, n, alpha, lo, hi, darts): the involutions of a stored G-map as one array of dart offsets, or NULL.
-- What makes tgsis.gmap_conditions fast. With the darts numbered densely
-- lo..hi (as tgsis.insert_gmap numbers them) and exactly one alpha row per
-- dart and level 0..n, the rows in key order (dartid, level) are an array
-- where the dart d has the offset b = (d - lo) * (n + 1) and element
-- b + l + 1 is the offset of alpha_l(d): a check is then a few array
-- subscripts per dart in one pass instead of a keyed join per condition
-- and level. ARRAY(SELECT ... ORDER BY) keeps the query's order (an
-- aggregate's input order is not promised); the key's order is the table's
-- when the rows were written in it, as tgsis.insert_gmap writes them.
-- NULL when the rows are not like that (missing, extra or dangling rows,
-- levels outside 0..n, holes in the numbering, more than 2^27 elements: an
-- array stays far below PostgreSQL's 1 GB per value): only the row-by-row
-- check (tgsis.gmap_conditions_by_rows) can then say what is wrong. A row
-- that does not fit is marked -1 in the same scan; N * (n + 1) elements
-- none of them -1 prove the shape, as the primary key (geoid, dartid,
-- level) allows one row per dart and level.
-- The darts' numbering (lo, hi, how many) comes from the caller
-- (tgsis.gmap_conditions reads it once for this function and the pass).
-- The tables are given as regclass (quoted by their output): no caller text
-- reaches the SQL unquoted.
-- enable_sort off: the rows in key order come from the primary key, never
-- from a sort; on tables just loaded (no statistics yet: a few thousand rows
-- guessed for millions) the planner otherwise sorts them on disk, 4x slower.
CREATE FUNCTION tgsis.gmap_alpha_array(p_geoid bigint, p_n integer, p_alpha regclass, p_lo bigint, p_hi bigint, p_darts bigint)
RETURNS integer[]
LANGUAGE plpgsql
STABLE
SET search_path FROM CURRENT
SET enable_sort = off
SET jit = off  -- a disabled plan node costs 1e10 on PostgreSQL < 18: JIT would compile what runs in ms
AS $$
DECLARE
    v_array integer[];
BEGIN
    IF coalesce(p_darts, 0) = 0 OR p_hi - p_lo + 1 <> p_darts OR p_darts * (p_n + 1) > 134217728 THEN
        RETURN NULL;
    END IF;
    EXECUTE format(
        'SELECT ARRAY(SELECT CASE WHEN level BETWEEN 0 AND $4 AND dartid BETWEEN $2 AND $3 AND dartid2 BETWEEN $2 AND $3
                                  THEN ((dartid2 - $2) * ($4 + 1))::integer ELSE -1 END
                        FROM %s WHERE geoid = $1 ORDER BY dartid, level)', p_alpha)
       INTO v_array USING p_geoid, p_lo, p_hi, p_n;
    IF cardinality(v_array) <> p_darts * (p_n + 1) OR array_position(v_array, -1) IS NOT NULL THEN
        RETURN NULL;
    END IF;
    RETURN v_array;
END
$$;

COMMENT ON FUNCTION tgsis.gmap_alpha_array(bigint, integer, regclass, bigint, bigint, bigint) IS
    'the involutions of a stored G-map as dart offsets (dart d at b = (d - lo) * (n + 1); element b + l + 1: the offset of alpha_l(d)), NULL unless there is exactly one alpha row per dart and level 0..n over the darts lo..hi (darts of them, numbered densely); what makes tgsis.gmap_conditions one pass';
