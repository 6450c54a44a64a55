-- tgsis.features_at(class, t, convention): the features of a class that exist at model time t.
CREATE FUNCTION tgsis.features_at(p_class text, p_t double precision, p_convention text DEFAULT 'left')
RETURNS SETOF bigint
LANGUAGE plpgsql
STABLE
AS $$
DECLARE
    v_class tgsis.catalog := tgsis.catalog_row(p_class);
BEGIN
    PERFORM tgsis.checked_time(p_t), tgsis.checked_convention(p_convention);
    IF v_class.timemodel NOT IN ('STATIC', 'MULTIDIM', 'INSTANTS', 'GMAP', 'EVOLVING') THEN   -- exists_at's rules
        PERFORM tgsis.no_model_rule(v_class.timemodel, 'tgsis.features_at', '{STATIC,MULTIDIM,INSTANTS,GMAP,EVOLVING}');
    END IF;
    RETURN QUERY EXECUTE format('SELECT f._geoid FROM %I.%I f WHERE tgsis.exists_at(f._geoid, $1, $2) ORDER BY f._geoid',
                                v_class.schemaname, v_class.featuretable)
        USING p_t, p_convention;
END
$$;

COMMENT ON FUNCTION tgsis.features_at(text, double precision, text) IS
    'ids of the features of a class that exist at model time t (static: all; temporal: from their first instant to their last, or for ever after if alive), ascending';
