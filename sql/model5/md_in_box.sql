-- tgsis.md_in_box(class, axes, low, high): the multiply indexed G-map features of a class whose extent meets a box over some of their axes.
-- E.g. the interpretations of a horizon that reach x in [0, 100] at knowledge
-- level 2: p_axes => '{x,knowledge}'. One GiST index scan (md_gmap_extent_idx)
-- per set of axes among the class's features (features may name their axes
-- differently; those lacking an asked axis are not in the box). An axis
-- that no feature of the class has is refused (TG100, naming it and the
-- class's axes) rather than answered with no feature. An extent is that of
-- the points without a NaN coordinate (tgsis.md_extent): a feature none of
-- whose points has a position has none and is in no box, by index and by
-- scan alike (tests/test_gmap_multidim.py forces both plans). An extent
-- holding a NaN (measured so before 0.3.0 and kept in a versioned database)
-- is in no box either, by both plans (tgsis.cube_has_nan: the index leaves it
-- out; tests/test_nan_boxes.py).
CREATE FUNCTION tgsis.md_in_box(p_class text, p_axes text[], p_low double precision[], p_high double precision[])
RETURNS SETOF bigint
LANGUAGE plpgsql
STABLE
AS $$
DECLARE
    v_class tgsis.catalog := tgsis.catalog_row(p_class);
    v_axes  text[];
    v_known text[];
    v_bad   text;
BEGIN
    IF v_class.timemodel IS DISTINCT FROM 'MULTIDIM' THEN
        RAISE EXCEPTION 'feature class % holds % features, not multiply indexed G-maps', p_class, v_class.timemodel
            USING ERRCODE = 'TG100', HINT = 'tgsis.geometries_in_box finds features of the other models by their 3D box';
    END IF;
    PERFORM tgsis.md_query_box(ARRAY[]::text[] || p_axes, p_axes, p_low, p_high);  -- a malformed box is an error even for an empty class
    EXECUTE format('SELECT array_agg(DISTINCT a ORDER BY a) FROM %I.%I f JOIN tgsis.md_gmap m ON m.geoid = f._geoid, unnest(m.axes) a',
                   v_class.schemaname, v_class.featuretable) INTO v_known;
    SELECT a INTO v_bad FROM unnest(p_axes) a WHERE v_known IS NOT NULL AND a <> ALL (v_known) LIMIT 1;
    IF v_bad IS NOT NULL THEN
        RAISE EXCEPTION 'no feature of class % has an axis %', p_class, quote_literal(left(v_bad, 100))
            USING ERRCODE = 'TG100', DETAIL = format('Their axes: %s.', array_to_string(v_known, ', ')),
                  HINT = 'p_axes names axes of the class''s features';
    END IF;
    FOR v_axes IN EXECUTE format('SELECT DISTINCT m.axes FROM %I.%I f JOIN tgsis.md_gmap m ON m.geoid = f._geoid',
                                 v_class.schemaname, v_class.featuretable) LOOP
        RETURN QUERY EXECUTE format(
            'SELECT f._geoid FROM %I.%I f JOIN tgsis.md_gmap m ON m.geoid = f._geoid
              WHERE m.axes = $1 AND m.extent && tgsis.md_query_box($1, $2, $3, $4) AND NOT tgsis.cube_has_nan(m.extent)
              ORDER BY f._geoid',
            v_class.schemaname, v_class.featuretable) USING v_axes, p_axes, p_low, p_high;
    END LOOP;
END
$$;

COMMENT ON FUNCTION tgsis.md_in_box(text, text[], double precision[], double precision[]) IS
    'model 5: ids of the features of a class of multiply indexed G-maps whose extent meets a box over some of their axes (unbounded on the others; the extent of the points without a NaN coordinate, none when no point has a position), by GiST index';
