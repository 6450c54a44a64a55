-- tgsis.gmap_conditions(geoid, n, darts, alpha, point, period): the conditions of an n-G-map over stored dart and alpha rows, with the offending darts.
-- Shared by the G-map models (model 4: tgsis.gmap_check over gmap_dart and
-- gmap_alpha with the period column; model 5: tgsis.md_check over md_dart
-- and md_alpha), which add their own (nodes, periods, points that exist).
-- (i) every alpha_i is an involution; (ii) no dart is free in alpha_i for
-- i < n; (iii) alpha_i o alpha_j is an involution for i + 2 <= j; the darts
-- of one 0-cell share their point (alpha_1 .. alpha_n keep it); the rows
-- refer to what exists (a row per dart and level, images that are darts);
-- with a period column, every alpha_i keeps a dart in its period (the
-- closure of the partition D0..Dk). darts lists the first offending darts
-- (at most 20), count all of them.
-- A valid map (the normal case) is proved valid in one statement
-- (tgsis.gmap_conditions_hold) and nothing more is done. Otherwise two ways
-- to the same answer say what is wrong: rows that read as arrays (as
-- tgsis.insert_gmap writes them) are checked in one pass over the darts
-- (tgsis.gmap_conditions_by_arrays); any other shape by keyed joins
-- (tgsis.gmap_conditions_by_rows), which also say what makes the rows
-- unreadable as arrays.
CREATE FUNCTION tgsis.gmap_conditions(p_geoid bigint, p_n integer, p_dart regclass, p_alpha regclass, p_point text,
                                      p_period text DEFAULT NULL)
RETURNS TABLE (problem text, count bigint, darts bigint[])
LANGUAGE plpgsql
STABLE
SET search_path FROM CURRENT
AS $$
DECLARE
    v_lo      bigint;
    v_hi      bigint;
    v_darts   bigint;
    v_several boolean;
    v_alpha   integer[];
    v_missing text;
    v_numbering text;
    v_dartset integer[];
BEGIN
    -- the function is callable by anyone: arguments that name no G-map's
    -- darts and involutions get an error of ours, not a missing column deep
    -- inside a generated query
    IF p_geoid IS NULL OR p_n IS NULL OR p_n < 0 OR p_dart IS NULL OR p_alpha IS NULL OR p_point IS NULL THEN
        RAISE EXCEPTION 'tgsis.gmap_conditions needs a geoid, a dimension n >= 0, the darts'' and involutions'' tables and the point column'
            USING ERRCODE = 'TG100', DETAIL = format('geoid %s, n %s, darts %s, alpha %s, point %s', p_geoid, p_n, p_dart, p_alpha, p_point),
                  HINT = 'tgsis.gmap_check(geoid) (model 4) and tgsis.md_check(geoid) (model 5) check a stored G-map';
    END IF;
    SELECT string_agg(format('%s.%s', c.rel, c.col), ', ') INTO v_missing
      FROM (SELECT p_dart AS rel, unnest(ARRAY['geoid', 'dartid', p_point] || CASE WHEN p_period IS NULL THEN '{}'::text[] ELSE ARRAY[p_period] END) AS col
            UNION ALL
            SELECT p_alpha, unnest(ARRAY['geoid', 'level', 'dartid', 'dartid2'])) AS c
     WHERE NOT EXISTS (SELECT FROM pg_catalog.pg_attribute a
                        WHERE a.attrelid = c.rel AND a.attname = c.col AND a.attnum > 0 AND NOT a.attisdropped);
    IF v_missing IS NOT NULL THEN
        RAISE EXCEPTION 'tgsis.gmap_conditions: % and % are not the darts and involutions of a G-map model', p_dart, p_alpha
            USING ERRCODE = 'TG100', DETAIL = format('missing columns: %s', v_missing),
                  HINT = 'tgsis.gmap_check(geoid) (model 4) and tgsis.md_check(geoid) (model 5) check a stored G-map';
    END IF;
    -- one scan of the darts for what both paths need: their numbering and
    -- whether they lie in more than one period (from the chunk rows when the darts are in chunks the caller reads:
    -- tgsis.gmap_chunk_arrays_sql; the face would decode every dart)
    SELECT c.numbering, c.dartset INTO v_numbering, v_dartset FROM tgsis.gmap_chunk_arrays_sql(p_dart, p_alpha, p_point, p_period) AS c;
    IF v_numbering IS NOT NULL THEN
        EXECUTE v_numbering INTO v_lo, v_hi, v_darts, v_several USING p_geoid, v_dartset;
    ELSE
        EXECUTE format('SELECT min(dartid), max(dartid), count(*), %s FROM %s WHERE geoid = $1',
                       CASE WHEN p_period IS NULL THEN 'false' ELSE format('min(%1$I) < max(%1$I)', p_period) END, p_dart)
           INTO v_lo, v_hi, v_darts, v_several USING p_geoid;
    END IF;
    -- a valid map ends here; the paths below say what is wrong
    IF tgsis.gmap_conditions_hold(p_geoid, p_n, p_dart, p_alpha, p_point, p_period, v_lo, v_hi, v_darts, v_several) THEN
        RETURN;
    END IF;
    v_alpha := tgsis.gmap_alpha_array(p_geoid, p_n, p_alpha, v_lo, v_hi, v_darts);
    IF v_alpha IS NULL THEN
        RETURN QUERY SELECT * FROM tgsis.gmap_conditions_by_rows(p_geoid, p_n, p_dart, p_alpha, p_point, p_period);
    ELSE
        RETURN QUERY SELECT * FROM tgsis.gmap_conditions_by_arrays(p_geoid, p_n, p_dart, p_point, p_period, v_alpha, v_lo, v_several);
    END IF;
END
$$;

COMMENT ON FUNCTION tgsis.gmap_conditions(bigint, integer, regclass, regclass, text, text) IS
    'the conditions of an n-G-map over stored dart and alpha rows (missing or dangling alpha rows, (i) involutions, (ii) no fixed point below alpha_n, (iii) alpha_i o alpha_j involutions for i + 2 <= j, one point per 0-cell, with a period column the periods'' closure) with the first offending darts; a valid map proved so in one statement (tgsis.gmap_conditions_hold), an invalid one searched in one pass over arrays when the rows allow it (tgsis.gmap_alpha_array), by keyed joins otherwise; shared by tgsis.gmap_check (model 4) and tgsis.md_check (model 5)';
