-- tgsis.checked_question(class, geoid, property, per_cell, op, value, convention): the catalog row of the temporal class a question "property op value" is asked of, once the question makes sense.
-- Checks, in this order: the class exists (TG200) and is temporal (TG100);
-- the property is a numeric per-instant property (column of <class>_pros) or,
-- with per_cell, a numeric vertex or cell property (<class>_cellpros) of it
-- (TG103, naming it); the operator (tgsis.checked_operator), the value (a
-- number: TG100 for NULL or NaN) and the convention (tgsis.checked_convention);
-- the feature is one of the class (TG200).
CREATE FUNCTION tgsis.checked_question(p_class text, p_geoid bigint, p_property text, p_per_cell boolean,
                                       p_op text, p_value double precision, p_convention text)
RETURNS tgsis.catalog
LANGUAGE plpgsql
STABLE
AS $$
DECLARE
    v_class tgsis.catalog := tgsis.catalog_row(p_class);
    v_what  text := CASE WHEN p_per_cell THEN lower(v_class.proalignment) ELSE 'per-instant' END;
    v_props jsonb := CASE WHEN p_per_cell THEN v_class.cell_properties ELSE v_class.instant_properties END;
    v_type  text;
    v_found boolean;
BEGIN
    IF v_class.timemodel = 'STATIC' THEN
        RAISE EXCEPTION 'feature class % is static: its properties do not change in time', p_class
            USING ERRCODE = 'TG100', HINT = 'temporal questions are asked of INSTANTS (model 2) and EVOLVING (model 3) classes';
    END IF;
    SELECT p ->> 'type' INTO v_type FROM jsonb_array_elements(v_props) p WHERE p ->> 'name' = p_property;
    IF v_type IS NULL THEN
        RAISE EXCEPTION 'feature class % has no % property %', p_class, v_what, coalesce(quote_literal(p_property), 'NULL')
            USING ERRCODE = 'TG103',
                  HINT = CASE WHEN EXISTS (SELECT FROM jsonb_array_elements(CASE WHEN p_per_cell THEN v_class.instant_properties
                                                                                 ELSE v_class.cell_properties END) p
                                            WHERE p ->> 'name' = p_property)
                              THEN format('%s is a %s property: ask tgsis.%s', p_property,
                                          CASE WHEN p_per_cell THEN 'per-instant' ELSE lower(v_class.proalignment) END,
                                          CASE WHEN p_per_cell THEN 'property_periods' ELSE 'first_time' END)
                              ELSE format('its %s properties: %s', v_what,
                                          coalesce((SELECT string_agg(p ->> 'name', ', ') FROM jsonb_array_elements(v_props) p),
                                                   'none'))
                         END;
    END IF;
    IF v_type NOT IN ('smallint', 'integer', 'bigint', 'real', 'double precision', 'numeric') THEN
        RAISE EXCEPTION '% property % of feature class % is %, not a number', v_what, p_property, p_class, v_type
            USING ERRCODE = 'TG103', HINT = 'conditions "value op v" are asked of numeric properties';
    END IF;
    PERFORM tgsis.checked_operator(p_op);
    IF p_value IS NULL OR p_value = 'NaN' THEN
        RAISE EXCEPTION 'the value % is compared with must be a number, not %', p_property, coalesce(p_value::text, 'NULL')
            USING ERRCODE = 'TG100', HINT = '-Infinity and Infinity are allowed';
    END IF;
    PERFORM tgsis.checked_convention(p_convention);
    EXECUTE format('SELECT EXISTS (SELECT FROM %I.%I WHERE _geoid = $1)', v_class.schemaname, v_class.featuretable)
       INTO v_found USING p_geoid;
    IF NOT v_found THEN
        RAISE EXCEPTION 'feature % is not a feature of class %', coalesce(p_geoid::text, 'NULL'), p_class
            USING ERRCODE = 'TG200', HINT = format('SELECT _geoid FROM %I.%I lists them', v_class.schemaname, v_class.featuretable);
    END IF;
    RETURN v_class;
END
$$;

COMMENT ON FUNCTION tgsis.checked_question(text, bigint, text, boolean, text, double precision, text) IS
    'the catalog row of the temporal class a question "property op value" is asked of, after checking it is temporal (TG100), the property is a numeric per-instant (or, per_cell, vertex/cell) property of it (TG103), op, value and convention (TG100) and that the feature is one of its (TG200)';
