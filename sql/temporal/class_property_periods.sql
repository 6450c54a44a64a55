-- tgsis.class_property_periods(class, property, op, value, convention): for every feature of a class, the periods over which "property op value" holds.
-- The source design's manager asked this of a whole class ("the features
-- whose throw exceeds 100 m, and when"): tgsis.property_periods for each
-- feature of the class, in one query. Features for which the condition
-- never holds give no row; the first row of a feature starts when the
-- property first satisfies the condition.
CREATE FUNCTION tgsis.class_property_periods(p_class text, p_property text, p_op text, p_value double precision,
                                             p_convention text DEFAULT 'left')
RETURNS TABLE (geoid bigint, period tgsis.timerange)
LANGUAGE plpgsql
STABLE
AS $$
DECLARE
    v_class tgsis.catalog := tgsis.catalog_row(p_class);
    v_first bigint;
BEGIN
    IF v_class.timemodel = 'STATIC' THEN
        RAISE EXCEPTION 'feature class % is static: its properties do not change in time', p_class
            USING ERRCODE = 'TG100', HINT = 'ask this of an INSTANTS or EVOLVING class';
    END IF;
    IF v_class.timemodel NOT IN ('INSTANTS', 'EVOLVING') THEN   -- property_periods's rules
        PERFORM tgsis.no_model_rule(v_class.timemodel, 'tgsis.class_property_periods', '{INSTANTS,EVOLVING}');
    END IF;
    EXECUTE format('SELECT min(_geoid) FROM %I.%I', v_class.schemaname, v_class.featuretable) INTO v_first;
    IF v_first IS NULL THEN
        RETURN;   -- no feature: nothing holds (and nothing to check the question against)
    END IF;
    -- the question checked once (property, operator, value, convention), with its errors, before the scan
    PERFORM tgsis.checked_question(p_class, v_first, p_property, false, p_op, p_value, p_convention);
    RETURN QUERY EXECUTE format(
        'SELECT f._geoid, p.period FROM %I.%I f, LATERAL tgsis.property_periods($1, f._geoid, $2, $3, $4, $5) p
          ORDER BY f._geoid, lower(p.period) NULLS FIRST',
        v_class.schemaname, v_class.featuretable)
      USING p_class, p_property, p_op, p_value, p_convention;
END
$$;

COMMENT ON FUNCTION tgsis.class_property_periods(text, text, text, double precision, text) IS
    'for every feature of a temporal class, the maximal periods over which a per-instant property satisfies "property op value" (tgsis.property_periods per feature), by feature and start';
