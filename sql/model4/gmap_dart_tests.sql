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
CREATE FUNCTION tgsis.gmap_dart_tests(p_n integer, p_several boolean, p_alpha text, p_points text, p_periods text,
                                      p_exact boolean)
RETURNS TABLE (columns text, tests text[], labels text[])
LANGUAGE plpgsql
IMMUTABLE
PARALLEL SAFE
SET search_path FROM CURRENT
AS $$
DECLARE
    v_stride integer := p_n + 1;
    v_i      integer;
    v_j      integer;
BEGIN
    columns := 'b';
    tests := '{}';
    labels := '{}';
    FOR v_i IN 0 .. p_n LOOP
        columns := columns || format(', %s[b + %s] AS a%s', p_alpha, v_i + 1, v_i);
    END LOOP;
    columns := columns || format(', %s[b / %s + 1] AS pt', p_points, v_stride);
    IF p_several THEN
        columns := columns || format(', %s[b / %s + 1] AS pr', p_periods, v_stride);
    END IF;
    FOR v_i IN 0 .. p_n LOOP                                          -- (i)
        labels := labels || format('alpha_%s is not an involution', v_i);
        tests := tests || format('%s[a%s + %s] = b', p_alpha, v_i, v_i + 1);
    END LOOP;
    FOR v_i IN 0 .. p_n - 1 LOOP                                      -- (ii)
        labels := labels || format('dart free in alpha_%s (only alpha_%s may have fixed points)', v_i, p_n);
        tests := tests || format('a%s <> b', v_i);
    END LOOP;
    FOR v_i IN 0 .. p_n - 2 LOOP                                      -- (iii)
        FOR v_j IN v_i + 2 .. p_n LOOP
            labels := labels || format('alpha_%s o alpha_%s is not an involution', v_i, v_j);
            tests := tests || CASE WHEN p_exact
                                   THEN format('%1$s[%1$s[%1$s[a%3$s + %4$s] + %5$s] + %4$s] = b', p_alpha, v_i, v_j, v_i + 1, v_j + 1)
                                   ELSE format('%1$s[a%2$s + %5$s] = %1$s[a%3$s + %4$s]', p_alpha, v_i, v_j, v_i + 1, v_j + 1) END;
        END LOOP;
    END LOOP;
    FOR v_i IN 1 .. p_n LOOP                                          -- one point per 0-cell
        labels := labels || format('alpha_%s joins darts of different points (a 0-cell has one point)', v_i);
        tests := tests || format('%s[a%s / %s + 1] = pt', p_points, v_i, v_stride);
    END LOOP;
    IF p_several THEN                                                 -- the periods' closure
        FOR v_i IN 0 .. p_n LOOP
            labels := labels || format('alpha_%s sends a dart into another topology period', v_i);
            tests := tests || format('%s[a%s / %s + 1] = pr', p_periods, v_i, v_stride);
        END LOOP;
    END IF;
    RETURN NEXT;
END
$$;

COMMENT ON FUNCTION tgsis.gmap_dart_tests(integer, boolean, text, text, text, boolean) IS
    'the per-dart tests of an n-G-map''s conditions as SQL text (the columns each dart''s images are read into, the tests that hold for a valid dart, the problem each names), shared by tgsis.gmap_conditions_hold and tgsis.gmap_conditions_by_arrays; exact: (iii) as (alpha_i alpha_j)^2 = id, otherwise as alpha_i alpha_j = alpha_j alpha_i';
