-- tgsis.gmap_property_at(class, geoid, property, t): the values of a numeric cell property of a G-map feature at model time t.
-- The class's property level's cells of the period containing t (acellid,
-- the _idx of the class's property table), each value linear between the
-- bracketing geometry instants, a + w (b - a), as EvolvingGMap.at computes
-- it; no rows when the feature does not exist at t; NULL values stay NULL.
CREATE FUNCTION tgsis.gmap_property_at(p_class text, p_geoid bigint, p_property text, p_t double precision)
RETURNS TABLE (acellid bigint, value double precision)
LANGUAGE plpgsql
STABLE
AS $$
DECLARE
    v_class tgsis.catalog := tgsis.catalog_row(p_class);
    v_found integer;
BEGIN
    IF v_class.celllevel IS NULL THEN
        RAISE EXCEPTION 'feature class % is not a class of G-maps', p_class
            USING ERRCODE = 'TG100', HINT = 'tgsis.property_at gives the property values of models 1 to 3';
    END IF;
    IF NOT EXISTS (SELECT FROM jsonb_array_elements(v_class.cell_properties) p
                    WHERE p ->> 'name' = p_property AND NOT p ? 'size'
                      AND p ->> 'type' IN ('smallint', 'integer', 'bigint', 'real', 'double precision', 'numeric')) THEN
        RAISE EXCEPTION 'feature class % has no numeric scalar cell property %', p_class, coalesce(quote_literal(p_property), 'NULL')
            USING ERRCODE = 'TG103',
                  HINT = format('its cell properties: %s',
                                coalesce((SELECT string_agg(p ->> 'name', ', ') FROM jsonb_array_elements(v_class.cell_properties) p),
                                         'none'));
    END IF;
    EXECUTE format('SELECT 1 FROM %I.%I WHERE _geoid = $1', v_class.schemaname, v_class.featuretable) INTO v_found USING p_geoid;
    IF v_found IS NULL THEN
        RAISE EXCEPTION 'feature class % has no feature %', p_class, p_geoid USING ERRCODE = 'TG200';
    END IF;
    PERFORM tgsis.checked_time(p_t);
    RETURN QUERY EXECUTE format(
        'WITH f AS MATERIALIZED (SELECT * FROM tgsis.gmap_frame($1, $2))
         SELECT a._idx, CASE WHEN (SELECT f.t0 = f.t1 FROM f) THEN a.%1$I::double precision
                             ELSE a.%1$I::double precision
                                  + (SELECT f.w FROM f) * (b.%1$I::double precision - a.%1$I::double precision) END
           FROM %2$I.%3$I a
           JOIN %2$I.%3$I b ON b._geoid = a._geoid AND b._timem = a._timem AND b._idx = a._idx
          WHERE a._geoid = $1 AND a._timem = (SELECT f.timem FROM f) AND a._timet = (SELECT f.t0 FROM f)
            AND b._timet = (SELECT f.t1 FROM f)
          ORDER BY a._idx',
        p_property, v_class.schemaname, v_class.cellprotable) USING p_geoid, p_t;
END
$$;

COMMENT ON FUNCTION tgsis.gmap_property_at(text, bigint, text, double precision) IS
    'model 4: values (acellid, value) of a numeric cell property of a G-map feature at t, linear between the bracketing geometry instants of the period containing t; none when the feature does not exist at t';
