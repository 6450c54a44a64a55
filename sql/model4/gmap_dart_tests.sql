-- tgsis.gmap_dart_tests(n, several, alpha, points, periods, exact): the per-dart tests of an n-G-map's conditions, as SQL text.
-- Shared by the two array passes over a stored G-map (tgsis.gmap_conditions_hold,
-- tgsis.gmap_conditions_by_arrays), so that both test the same conditions in
-- the same order and words. columns reads each dart's images, point and
-- period once (b: the dart's offset; a_l: the offset of alpha_l of it; pt,
-- pr: its point and period), from the arrays named by alpha, points and
-- periods (fragments of the caller's statement: '$1', 's.a', never user
-- text); tests are what holds for a valid dart, labels the problem each
-- names. exact: (iii) as alpha_i alpha_j alpha_i alpha_j (d) = d, which names
-- exactly the darts where it fails; otherwise as alpha_j alpha_i (d) =
-- alpha_i alpha_j (d), one array read fewer, equivalent once every alpha_i is
-- an involution (the caller tests that too).
-- p_layout: how the arrays are laid out. NULL (the rows' layout, dart
-- order): the dart at offset b = (d - lo) * (n + 1), alpha_l of it at
-- alpha[b + l + 1], its point at points[b / (n + 1) + 1]. ARRAY[k, s] (the
-- chunk arrays' layout, tgsis.gmap_chunk_arrays_sql): the dart at offset
-- b = d - base over k chunks of s slots; alpha is 2-D, a row per level and
-- chunk (level-major), alpha_l of it at alpha_base[r] + alpha[r][b % s + 1],
-- r = l * k + b / s + 1 (the chunk's vbase less base, and the relative
-- image); points likewise, a row per chunk, with points_base; periods a row
-- per chunk (<name>_base: the fragment's name with _base appended). There
-- the caller selects derived (each image's row q<l> and slot s<l>) from the
-- columns in a subquery of their own (OFFSET 0: computed once per dart),
-- and the tests read them: no division per read.
CREATE FUNCTION tgsis.gmap_dart_tests(p_n integer, p_several boolean, p_alpha text, p_points text, p_periods text,
                                      p_exact boolean, p_layout integer[] DEFAULT NULL)
RETURNS TABLE (columns text, tests text[], labels text[], derived text)
LANGUAGE plpgsql
IMMUTABLE
PARALLEL SAFE
SET search_path FROM CURRENT
AS $$
DECLARE
    v_stride integer := p_n + 1;
    v_i      integer;
    v_j      integer;
    v_at     text[] := '{}';  -- v_at[l + 1]: the read of alpha_l of a dart (a format of the dart's two arguments)
    v_pt     text;             -- the read of the point of a dart
    v_pr     text;             -- and of its period
    v_q      text[] := '{}';  -- v_q[l + 1], v_s[l + 1]: alpha_l of the dart b as the reads' two arguments
    v_s      text[] := '{}';
    v_bq     text;             -- the dart b so
    v_bs     text;
BEGIN
    -- the rows' layout: a dart is its offset (the first argument; the second unused). The chunks': a dart is its
    -- row and slot (d / s + 1 and d % s + 1 of its offset d from base), computed once per image (derived)
    IF p_layout IS NULL THEN
        FOR v_i IN 0 .. p_n LOOP
            v_at := v_at || format('%s[%%1$s + %s]', p_alpha, v_i + 1);
            v_q := v_q || ('a' || v_i);
            v_s := v_s || ''::text;
        END LOOP;
        v_pt := format('%s[%%1$s / %s + 1]', p_points, v_stride);
        v_pr := format('%s[%%1$s / %s + 1]', p_periods, v_stride);
        v_bq := 'b';
        v_bs := '';
    ELSE
        FOR v_i IN 0 .. p_n LOOP
            v_at := v_at || format('(%1$s_base[%2$s + %%1$s] + %1$s[%2$s + %%1$s][%%2$s])', p_alpha, v_i * p_layout[1]);
            v_q := v_q || ('q' || v_i);
            v_s := v_s || ('s' || v_i);
            derived := concat_ws(', ', derived, format('a%1$s / %2$s + 1 AS q%1$s, a%1$s %% %2$s + 1 AS s%1$s', v_i, p_layout[2]));
        END LOOP;
        v_pt := format('(%1$s_base[%%1$s] + %1$s[%%1$s][%%2$s])', p_points);
        v_pr := format('%s[%%1$s][%%2$s]', p_periods);
        v_bq := format('(b / %s + 1)', p_layout[2]);
        v_bs := format('(b %% %s + 1)', p_layout[2]);
        IF p_exact THEN
            RAISE EXCEPTION 'tgsis.gmap_dart_tests: the exact form reads the chunk arrays'' layout nowhere'
                USING ERRCODE = 'TG100', HINT = 'p_exact with p_layout NULL (tgsis.gmap_conditions_by_arrays)';
        END IF;
    END IF;
    columns := 'b';
    tests := '{}';
    labels := '{}';
    FOR v_i IN 0 .. p_n LOOP
        columns := columns || format(', %s AS a%s', format(v_at[v_i + 1], v_bq, v_bs), v_i);
    END LOOP;
    columns := columns || format(', %s AS pt', format(v_pt, v_bq, v_bs));
    IF p_several THEN
        columns := columns || format(', %s AS pr', format(v_pr, v_bq, v_bs));
    END IF;
    FOR v_i IN 0 .. p_n LOOP                                          -- (i)
        labels := labels || format('alpha_%s is not an involution', v_i);
        tests := tests || format('%s = b', format(v_at[v_i + 1], v_q[v_i + 1], v_s[v_i + 1]));
    END LOOP;
    FOR v_i IN 0 .. p_n - 1 LOOP                                      -- (ii)
        labels := labels || format('dart free in alpha_%s (only alpha_%s may have fixed points)', v_i, p_n);
        tests := tests || format('a%s <> b', v_i);
    END LOOP;
    FOR v_i IN 0 .. p_n - 2 LOOP                                      -- (iii)
        FOR v_j IN v_i + 2 .. p_n LOOP
            labels := labels || format('alpha_%s o alpha_%s is not an involution', v_i, v_j);
            tests := tests || CASE WHEN p_exact   -- (the rows' layout only: a dart is its offset)
                                   THEN format('%s = b', format(v_at[v_i + 1], format(v_at[v_j + 1], format(v_at[v_i + 1], 'a' || v_j))))
                                   ELSE format('%s = %s', format(v_at[v_j + 1], v_q[v_i + 1], v_s[v_i + 1]),
                                               format(v_at[v_i + 1], v_q[v_j + 1], v_s[v_j + 1])) END;
        END LOOP;
    END LOOP;
    FOR v_i IN 1 .. p_n LOOP                                          -- one point per 0-cell
        labels := labels || format('alpha_%s joins darts of different points (a 0-cell has one point)', v_i);
        tests := tests || format('%s = pt', format(v_pt, v_q[v_i + 1], v_s[v_i + 1]));
    END LOOP;
    IF p_several THEN                                                 -- the periods' closure
        FOR v_i IN 0 .. p_n LOOP
            labels := labels || format('alpha_%s sends a dart into another topology period', v_i);
            tests := tests || format('%s = pr', format(v_pr, v_q[v_i + 1], v_s[v_i + 1]));
        END LOOP;
    END IF;
    RETURN NEXT;
END
$$;

COMMENT ON FUNCTION tgsis.gmap_dart_tests(integer, boolean, text, text, text, boolean, integer[]) IS
    'the per-dart tests of an n-G-map''s conditions as SQL text (the columns each dart''s images are read into, the tests that hold for a valid dart, the problem each names), shared by tgsis.gmap_conditions_hold and tgsis.gmap_conditions_by_arrays; exact: (iii) as (alpha_i alpha_j)^2 = id, otherwise as alpha_i alpha_j = alpha_j alpha_i; layout NULL: the arrays in dart order (offset b = (d - lo) * (n + 1), alpha_l at b + l + 1), ARRAY[k, s]: the chunk arrays, a row per level and chunk of s slots (tgsis.gmap_chunk_arrays_sql)';
