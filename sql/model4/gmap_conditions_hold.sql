-- tgsis.gmap_conditions_hold(geoid, n, darts, alpha, point, period, lo, hi, count, several): whether a stored G-map meets every condition, in one statement.
-- What makes tgsis.gmap_conditions fast on a valid map: it only has to say
-- "nothing is wrong", and saying which darts are wrong (tgsis.gmap_conditions_by_arrays,
-- _by_rows) is left to the maps where something is. One statement reads
-- the involutions as one array of dart offsets (rows in key order, as in
-- tgsis.gmap_alpha_array) and the darts' points (and periods) as arrays,
-- then looks for a dart failing a condition and stops at the first.
-- Why it is one statement: arrays held in PL/pgSQL variables are expanded
-- (one Datum per element: 144 MB for 18M offsets, seconds to build and
-- caches missed); arrays that stay values of the statement are read flat.
-- Why each test is the cheapest equivalent: the conditions are checked
-- together, and when every alpha_i is an involution (i), alpha_i o alpha_j
-- is one (iii) exactly when alpha_i and alpha_j commute on every dart:
-- (ai aj)^2 = id <=> ai aj = (ai aj)^-1 = aj ai. So (iii) is tested as
-- alpha_j(alpha_i(d)) = alpha_i(alpha_j(d)), two array reads instead of
-- three; a dart may then fail the other form but not this one (or the
-- reverse) only where (i) fails too, and then the map is not valid either
-- way. Every test must come out true: out-of-range reads (NULL) fail it.
-- The shape of the rows is proved as tgsis.gmap_alpha_array proves it, but
-- cheaper: the darts are lo..hi (count of them, from the caller), every
-- alpha row's dart lies there (the ends of the key), every level is 0..n,
-- and there are count * (n + 1) rows (the key allows one per dart and
-- level): the rows in key order are then exactly the array's elements. A
-- row of another level or an image outside lo..hi becomes NULL and fails.
-- false says only "not proved valid": the caller then runs the exact path.
-- The tables are given as regclass (quoted by their output), the columns
-- by name (%I), the offsets are integers: no caller text reaches the SQL
-- unquoted.
-- enable_sort off: the rows in key order come from the primary key, never
-- from a sort (tables just loaded have no statistics; the planner would
-- sort 18M rows on disk).
-- Darts and involutions stored in chunks (docs/storage.md, "G-maps"): the
-- faces would decode every slot and sort the involutions by (dartid,
-- level), which the chunk keys (geoid, level, chunk) do not give in order
-- (3.2x rows on 8^3 cubes). The arrays are then the chunk tables' own
-- (tgsis.gmap_chunk_arrays_sql: a row per chunk version the session sees,
-- with its vbase; only the chunk rows are sorted), and the same tests are
-- made on that layout (tgsis.gmap_dart_tests' ARRAY[k, s]). Read as the
-- caller, under the chunk tables' row-level security (the faces when the
-- caller may read the faces only).
CREATE FUNCTION tgsis.gmap_conditions_hold(p_geoid bigint, p_n integer, p_dart regclass, p_alpha regclass, p_point text,
                                           p_period text, p_lo bigint, p_hi bigint, p_darts bigint, p_several boolean)
RETURNS boolean
LANGUAGE plpgsql
STABLE
SET search_path FROM CURRENT
SET enable_sort = off
SET jit = off  -- a disabled plan node costs 1e10 on PostgreSQL < 18: JIT would compile what runs in ms
AS $$
DECLARE
    v_stride  integer := p_n + 1;
    v_several boolean := p_several AND p_period IS NOT NULL;
    v_columns text;
    v_arrays  text;
    v_tests   text[];
    v_holds   boolean;
    v_chunks  record;
    v_k       integer;
    v_derived text;
BEGIN
    IF coalesce(p_darts, 0) = 0 OR p_hi - p_lo + 1 <> p_darts OR p_darts * v_stride > 134217728 THEN
        RETURN false;
    END IF;
    SELECT * INTO v_chunks FROM tgsis.gmap_chunk_arrays_sql(p_dart, p_alpha, p_point, CASE WHEN v_several THEN p_period END);
    IF v_chunks.arrays IS NOT NULL AND p_lo >= 0 THEN
        -- the chunks lo / s .. hi / s, k of them, a row each (and per level); base: the first one's first id
        v_k := (p_hi / v_chunks.size - p_lo / v_chunks.size + 1)::integer;
        SELECT t.columns, t.tests, t.derived INTO v_columns, v_tests, v_derived
          FROM tgsis.gmap_dart_tests(p_n, v_several, 's.a', 's.p', 's.r', false, ARRAY[v_k, v_chunks.size]) AS t;
        EXECUTE format('SELECT s.shape AND NOT EXISTS (SELECT FROM (SELECT *, %s FROM (SELECT %s FROM generate_series(($3 - $5)::integer, ($4 - $5)::integer) AS b
                                                                                     OFFSET 0) AS d0 OFFSET 0) AS d
                                                        WHERE (%s) IS NOT TRUE)
                          FROM (%s OFFSET 0) AS s',
                       v_derived, v_columns, array_to_string(v_tests, ' AND '), v_chunks.arrays)
           INTO v_holds
          USING p_geoid, p_n, p_lo, p_hi, (p_lo / v_chunks.size) * v_chunks.size, v_k,
                v_chunks.dartset, v_chunks.alphaset, v_chunks.size, p_darts;
        RETURN coalesce(v_holds, false);
    END IF;
    -- every alpha row's dart is one of lo..hi (the key's ends: no scan)
    EXECUTE format('SELECT min(dartid) >= $2 AND max(dartid) <= $3 FROM %s WHERE geoid = $1', p_alpha)
       INTO v_holds USING p_geoid, p_lo, p_hi;
    IF v_holds IS NOT TRUE THEN
        RETURN false;
    END IF;
    -- the arrays: s.a the images as dart offsets (a row of a level outside
    -- 0..n or an image outside lo..hi: NULL), s.p the darts' points, s.r
    -- their periods, in dart order
    v_arrays := format('ARRAY(SELECT CASE WHEN level BETWEEN 0 AND $2 AND dartid2 BETWEEN $3 AND $4
                                          THEN ((dartid2 - $3) * %s)::integer END
                                FROM %s WHERE geoid = $1 ORDER BY dartid, level) AS a, '
                       'ARRAY(SELECT %I::bigint FROM %s WHERE geoid = $1 ORDER BY dartid) AS p',
                       v_stride, p_alpha, p_point, p_dart);
    IF v_several THEN
        v_arrays := v_arrays || format(', ARRAY(SELECT %I::double precision FROM %s WHERE geoid = $1 ORDER BY dartid) AS r',
                                       p_period, p_dart);
    END IF;
    SELECT t.columns, t.tests INTO v_columns, v_tests FROM tgsis.gmap_dart_tests(p_n, v_several, 's.a', 's.p', 's.r', false) AS t;
    EXECUTE format('SELECT cardinality(s.a) = $5
                           AND NOT EXISTS (SELECT FROM (SELECT %s FROM generate_series(0, $5 - %s, %s) AS b OFFSET 0) AS d
                                            WHERE (%s) IS NOT TRUE)
                      FROM (SELECT %s OFFSET 0) AS s',
                   v_columns, v_stride, v_stride, array_to_string(v_tests, ' AND '), v_arrays)
       INTO v_holds USING p_geoid, p_n, p_lo, p_hi, (p_darts * v_stride)::integer;
    RETURN coalesce(v_holds, false);
END
$$;

COMMENT ON FUNCTION tgsis.gmap_conditions_hold(bigint, integer, regclass, regclass, text, text, bigint, bigint, bigint, boolean) IS
    'true when a stored G-map meets every condition of tgsis.gmap_conditions (rows of one alpha per dart and level, (i), (ii), (iii), one point per 0-cell, the periods'' closure), proved in one statement over the rows read as flat arrays; false: not proved (tgsis.gmap_conditions then says what is wrong)';
