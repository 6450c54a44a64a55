-- tgsis.property_at(class, geoid, property, t, convention): the values of a numeric vertex or cell property of a feature at model time t.
-- What the snapshot at t (tgsis.vertices_at, tgsis.triangles_at) leaves out:
-- the property values that go with it, one row per vertex or node (VERTEX
-- classes) or triangle (CELL), idx as in the snapshot. Model 3: linear
-- between the bracketing geometry instants of the period containing t,
-- a + w (b - a), the formula EvolvingSurface.at uses (equal to the bit);
-- model 2: the values of the instant the step convention chooses; static:
-- the stored values at every t. No rows when the feature does not exist at
-- t; NULL values stay NULL.
CREATE FUNCTION tgsis.property_at(p_class text, p_geoid bigint, p_property text, p_t double precision,
                                  p_convention text DEFAULT 'left')
RETURNS TABLE (idx bigint, value double precision)
LANGUAGE plpgsql
STABLE
AS $$
DECLARE
    v_class tgsis.catalog := tgsis.catalog_row(p_class);
BEGIN
    IF v_class.timemodel = 'STATIC' THEN
        -- the question's checks (a numeric vertex or cell property, the feature one of the class) for a static class
        -- (a scalar property of the class's own alignment: the others live in otherprotable, vectors have sizes)
        IF NOT EXISTS (SELECT FROM jsonb_array_elements(v_class.cell_properties) p
                        WHERE p ->> 'name' = p_property AND NOT p ? 'size' AND NOT p ? 'alignment'
                          AND p ->> 'type' IN ('smallint', 'integer', 'bigint', 'real', 'double precision', 'numeric')) THEN
            RAISE EXCEPTION 'feature class % has no numeric scalar % property %', p_class, lower(v_class.proalignment),
                    coalesce(quote_literal(p_property), 'NULL')
                USING ERRCODE = 'TG103',
                      HINT = format('its %s properties: %s', lower(v_class.proalignment),
                                    coalesce((SELECT string_agg(p ->> 'name', ', ') FROM jsonb_array_elements(v_class.cell_properties) p),
                                             'none'));
        END IF;
        PERFORM tgsis.checked_time(p_t), tgsis.checked_convention(p_convention);
        RETURN QUERY EXECUTE format('SELECT p._idx, p.%I::double precision FROM %I.%I p WHERE p._geoid = $1 ORDER BY p._idx',
                                    p_property, v_class.schemaname, v_class.cellprotable) USING p_geoid;
        RETURN;
    END IF;
    IF v_class.timemodel NOT IN ('INSTANTS', 'EVOLVING') THEN
        PERFORM tgsis.no_model_rule(v_class.timemodel, 'tgsis.property_at', '{STATIC,INSTANTS,EVOLVING}');
    END IF;
    PERFORM tgsis.checked_question(p_class, p_geoid, p_property, true, '=', 0, p_convention);
    PERFORM tgsis.checked_time(p_t);
    IF v_class.timemodel = 'INSTANTS' THEN
        RETURN QUERY EXECUTE format(
            'SELECT p._idx, p.%I::double precision FROM %I.%I p
              WHERE p._geoid = $1 AND p._times = tgsis.instant_at($1, $2, $3) ORDER BY p._idx',
            p_property, v_class.schemaname, v_class.cellprotable) USING p_geoid, p_t, p_convention;
    ELSE
        RETURN QUERY EXECUTE format(
            'WITH f AS MATERIALIZED (SELECT * FROM tgsis.evolving_frame($1, $2))
             SELECT a._idx, CASE WHEN (SELECT f.t0 = f.t1 FROM f) THEN a.%1$I::double precision
                                 ELSE a.%1$I::double precision
                                      + (SELECT f.w FROM f) * (b.%1$I::double precision - a.%1$I::double precision) END
               FROM %2$I.%3$I a
               JOIN %2$I.%3$I b ON b._geoid = a._geoid AND b._timem = a._timem AND b._idx = a._idx
              WHERE a._geoid = $1 AND a._timem = (SELECT f.timem FROM f) AND a._timet = (SELECT f.t0 FROM f)
                AND b._timet = (SELECT f.t1 FROM f)
              ORDER BY a._idx',
            p_property, v_class.schemaname, v_class.cellprotable) USING p_geoid, p_t;
    END IF;
END
$$;

COMMENT ON FUNCTION tgsis.property_at(text, bigint, text, double precision, text) IS
    'values (idx, value) of a numeric vertex or cell property of a feature at model time t: model 3 interpolated as the snapshot is, model 2 by the step convention, static ones always; none when the feature does not exist at t';
