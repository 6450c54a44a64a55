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
-- The table is given as regclass, the columns by name (%I), the labels as
-- literals (%L), the offsets are integers: no caller text reaches the SQL
-- unquoted.
-- enable_sort off: the rows in key order come from the primary key, never
-- from a sort; on tables just loaded (no statistics yet: a few thousand rows
-- guessed for millions) the planner otherwise sorts them on disk, 4x slower.
CREATE FUNCTION tgsis.gmap_conditions_by_arrays(p_geoid bigint, p_n integer, p_dart regclass, p_point text, p_period text,
                                                p_alpha integer[])
RETURNS TABLE (problem text, count bigint, darts bigint[])
LANGUAGE plpgsql
STABLE
SET search_path FROM CURRENT
SET enable_sort = off
AS $$
DECLARE
    v_stride  integer := p_n + 1;
    v_size    integer := cardinality(p_alpha) / (p_n + 1);
    v_lo      bigint;
    v_points  bigint[];
    v_periods double precision[];
    v_several boolean := false;
    v_labels  text[] := '{}';
    v_tests   text[] := '{}';
    v_flags   text;
    v_any     text;
    v_aggs    text;
    v_failing integer[];
    v_rows    text;
    v_i       integer;
    v_j       integer;
BEGIN
    EXECUTE format('SELECT min(dartid), %s FROM %s WHERE geoid = $1',
                   CASE WHEN p_period IS NULL THEN 'false' ELSE format('min(%1$I) < max(%1$I)', p_period) END, p_dart)
       INTO v_lo, v_several USING p_geoid;
    EXECUTE format('SELECT ARRAY(SELECT %I::bigint FROM %s WHERE geoid = $1 ORDER BY dartid)', p_point, p_dart)
       INTO v_points USING p_geoid;
    IF v_several THEN
        EXECUTE format('SELECT ARRAY(SELECT %I::double precision FROM %s WHERE geoid = $1 ORDER BY dartid)', p_period, p_dart)
           INTO v_periods USING p_geoid;
    END IF;
    -- the conditions in tgsis.gmap_conditions_by_rows' order; b is the
    -- dart's offset, $1[b + l + 1] the offset of its alpha_l, b / stride + 1
    -- its place in the point and period arrays
    FOR v_i IN 0 .. p_n LOOP                                          -- (i)
        v_labels := v_labels || format('alpha_%s is not an involution', v_i);
        v_tests := v_tests || format('$1[$1[b + %1$s] + %1$s] <> b', v_i + 1);
    END LOOP;
    FOR v_i IN 0 .. p_n - 1 LOOP                                      -- (ii)
        v_labels := v_labels || format('dart free in alpha_%s (only alpha_%s may have fixed points)', v_i, p_n);
        v_tests := v_tests || format('$1[b + %s] = b', v_i + 1);
    END LOOP;
    FOR v_i IN 0 .. p_n - 2 LOOP                                      -- (iii)
        FOR v_j IN v_i + 2 .. p_n LOOP
            v_labels := v_labels || format('alpha_%s o alpha_%s is not an involution', v_i, v_j);
            v_tests := v_tests || format('$1[$1[$1[$1[b + %2$s] + %1$s] + %2$s] + %1$s] <> b', v_i + 1, v_j + 1);
        END LOOP;
    END LOOP;
    FOR v_i IN 1 .. p_n LOOP                                          -- one point per 0-cell
        v_labels := v_labels || format('alpha_%s joins darts of different points (a 0-cell has one point)', v_i);
        v_tests := v_tests || format('$2[$1[b + %1$s] / %2$s + 1] <> $2[b / %2$s + 1]', v_i + 1, v_stride);
    END LOOP;
    IF v_several THEN                                                 -- the periods' closure
        FOR v_i IN 0 .. p_n LOOP
            v_labels := v_labels || format('alpha_%s sends a dart into another topology period', v_i);
            v_tests := v_tests || format('$3[$1[b + %1$s] / %2$s + 1] <> $3[b / %2$s + 1]', v_i + 1, v_stride);
        END LOOP;
    END IF;
    SELECT string_agg(format('%s AS c%s', t.test, t.i), ', ' ORDER BY t.i),
           string_agg(format('(%s)', t.test), ' OR ' ORDER BY t.i),
           string_agg(format('count(*) FILTER (WHERE c%1$s) AS n%1$s, (array_agg(b ORDER BY b) FILTER (WHERE c%1$s))[1:20] AS d%1$s',
                             t.i), ', ' ORDER BY t.i),
           string_agg(format('(%1$s, %2$L, s.n%1$s, s.d%1$s)', t.i, v_labels[t.i]), ', ' ORDER BY t.i)
      INTO v_flags, v_any, v_aggs, v_rows
      FROM unnest(v_tests) WITH ORDINALITY AS t (test, i);
    -- one pass over every dart's offset (streamed: a set-returning function
    -- in the select list is not stored first) keeps those failing a test;
    -- a valid map ends here
    EXECUTE format('SELECT array_agg(b) FROM (SELECT generate_series(0, $5 - %s, %s) AS b) AS offsets WHERE %s',
                   v_stride, v_stride, v_any)
       INTO v_failing USING p_alpha, v_points, v_periods, v_lo, cardinality(p_alpha);
    IF v_failing IS NULL THEN
        RETURN;
    END IF;
    -- the failing darts only: which tests each fails, counted per test
    RETURN QUERY EXECUTE format(
        'SELECT v.problem, v.count, (SELECT array_agg(x / %s + $4 ORDER BY x) FROM unnest(v.darts) AS x)
           FROM (SELECT %s FROM (SELECT b, %s FROM unnest($5) AS b) AS failing) AS s
          CROSS JOIN LATERAL (VALUES %s) AS v (i, problem, count, darts)
          WHERE v.count > 0
          ORDER BY v.i', v_stride, v_aggs, v_flags, v_rows)
        USING p_alpha, v_points, v_periods, v_lo, v_failing;
END
$$;

COMMENT ON FUNCTION tgsis.gmap_conditions_by_arrays(bigint, integer, regclass, text, text, integer[]) IS
    'tgsis.gmap_conditions in one pass over the darts read as an array (tgsis.gmap_alpha_array); the same problems, in the same order and words, as tgsis.gmap_conditions_by_rows';
