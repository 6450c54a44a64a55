-- tgsis.gmap_conditions_by_arrays(geoid, n, darts, point, period, alpha): tgsis.gmap_conditions in one pass over dart offsets.
-- The rows read as an array (tgsis.gmap_alpha_array: the dart at offset b,
-- alpha_l of it at offset $1[b + l + 1]; the darts' points and periods in
-- dart order), every condition is a few array subscripts per dart,
-- evaluated in one scan of the offsets; only the darts that fail one are
-- kept, and then counted per condition. A 6M-dart map is checked in seconds where
-- a keyed join per condition and level took minutes. The problems, their
-- order and their wording are those of tgsis.gmap_conditions_by_rows (the
-- tests compare the two). What holds by construction of the array (one row
-- per dart and level, images that are darts) is not checked again; with
-- one period only, no alpha_i can leave it.
-- The darts' facts come from the caller (tgsis.gmap_conditions reads them
-- once for both functions): p_lo the first dart id, p_several whether the
-- darts lie in more than one period.
-- The table is given as regclass, the columns by name (%I), the labels as
-- literals (%L), the offsets are integers: no caller text reaches the SQL
-- unquoted.
-- enable_sort off: the rows in key order come from the primary key, never
-- from a sort; on tables just loaded (no statistics yet: a few thousand rows
-- guessed for millions) the planner otherwise sorts them on disk, 4x slower.
CREATE FUNCTION tgsis.gmap_conditions_by_arrays(p_geoid bigint, p_n integer, p_dart regclass, p_point text, p_period text,
                                                p_alpha integer[], p_lo bigint, p_several boolean)
RETURNS TABLE (problem text, count bigint, darts bigint[])
LANGUAGE plpgsql
STABLE
SET search_path FROM CURRENT
SET enable_sort = off
SET jit = off  -- a disabled plan node costs 1e10 on PostgreSQL < 18: JIT would compile what runs in ms
AS $$
DECLARE
    v_stride  integer := p_n + 1;
    v_points  bigint[];
    v_periods double precision[];
    v_several boolean := p_several AND p_period IS NOT NULL;
    v_columns text;
    v_labels  text[];
    v_tests   text[];
    v_flags   text;
    v_any     text;
    v_aggs    text;
    v_failing integer[];
    v_rows    text;
BEGIN
    EXECUTE format('SELECT ARRAY(SELECT %I::bigint FROM %s WHERE geoid = $1 ORDER BY dartid)', p_point, p_dart)
       INTO v_points USING p_geoid;
    IF v_several THEN
        EXECUTE format('SELECT ARRAY(SELECT %I::double precision FROM %s WHERE geoid = $1 ORDER BY dartid)', p_period, p_dart)
           INTO v_periods USING p_geoid;
    END IF;
    -- each dart's images, point and period, read once per dart in a
    -- subquery (OFFSET 0 keeps it) that every test reuses; the tests in
    -- tgsis.gmap_conditions_by_rows' order, each failing where it does not hold
    SELECT t.columns, t.tests, t.labels INTO v_columns, v_tests, v_labels
      FROM tgsis.gmap_dart_tests(p_n, v_several, '$1', '$2', '$3', true) AS t;
    SELECT string_agg(format('(%s) IS NOT TRUE AS c%s', t.test, t.i), ', ' ORDER BY t.i),
           format('(%s) IS NOT TRUE', string_agg(format('(%s)', t.test), ' AND ' ORDER BY t.i)),
           string_agg(format('count(*) FILTER (WHERE c%1$s) AS n%1$s, (array_agg(b ORDER BY b) FILTER (WHERE c%1$s))[1:20] AS d%1$s',
                             t.i), ', ' ORDER BY t.i),
           string_agg(format('(%1$s, %2$L, s.n%1$s, s.d%1$s)', t.i, v_labels[t.i]), ', ' ORDER BY t.i)
      INTO v_flags, v_any, v_aggs, v_rows
      FROM unnest(v_tests) WITH ORDINALITY AS t (test, i);
    -- one pass over every dart's offset (streamed: a set-returning function
    -- in the select list is not stored first) keeps those failing a test;
    -- a valid map ends here
    EXECUTE format('SELECT array_agg(b) FROM (SELECT %s FROM (SELECT generate_series(0, $4 - %s, %s) AS b) AS o OFFSET 0) AS d
                     WHERE %s',
                   v_columns, v_stride, v_stride, v_any)
       INTO v_failing USING p_alpha, v_points, v_periods, cardinality(p_alpha);
    IF v_failing IS NULL THEN
        RETURN;
    END IF;
    -- the failing darts only: which tests each fails, counted per test
    RETURN QUERY EXECUTE format(
        'SELECT v.problem, v.count, (SELECT array_agg(x / %s + $4 ORDER BY x) FROM unnest(v.darts) AS x)
           FROM (SELECT %s FROM (SELECT b, %s FROM (SELECT %s FROM unnest($5) AS b OFFSET 0) AS d) AS failing) AS s
          CROSS JOIN LATERAL (VALUES %s) AS v (i, problem, count, darts)
          WHERE v.count > 0
          ORDER BY v.i', v_stride, v_aggs, v_flags, v_columns, v_rows)
        USING p_alpha, v_points, v_periods, p_lo, v_failing;
END
$$;

COMMENT ON FUNCTION tgsis.gmap_conditions_by_arrays(bigint, integer, regclass, text, text, integer[], bigint, boolean) IS
    'tgsis.gmap_conditions in one pass over the darts read as an array (tgsis.gmap_alpha_array); the same problems, in the same order and words, as tgsis.gmap_conditions_by_rows';
