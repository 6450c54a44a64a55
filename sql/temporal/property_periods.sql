-- tgsis.property_periods(class, geoid, property, op, value, convention): the maximal intervals of model time over which "property op value" holds for a per-instant property of a feature, ascending.
-- Model 2 (INSTANTS): the value of instant t_i holds in its step interval
-- (tgsis.instant_periods: left-closed '[t_i, t_i+1)', the last '[t_k, t_k]';
-- right-closed '(t_i-1, t_i]', the first '[t_0, t_0]'; after the last '[t_k,)'
-- or '(t_k-1,)' if alive). Model 3 (EVOLVING): the value is linear between
-- consecutive geometry instants of a topology period, crossing times by linear
-- interpolation, bounds closed for <=, >=, = and open for <, >, <> at a
-- crossing (tgsis.evolving_satisfied); convention is not used. NULL or NaN
-- values are unknown: never satisfied, nor the stretches next to them
-- (model 3). Adjacent pieces are merged ('[1,2)' and '[2,3)' give '[1,3)').
-- An alive feature keeps its last value: the last interval may be unbounded
-- ('[t,)'). When the property first satisfies the condition is
-- lower(period) of the first row (open lower bound: right after it).
CREATE FUNCTION tgsis.property_periods(p_class text, p_geoid bigint, p_property text, p_op text,
                                       p_value double precision, p_convention text DEFAULT 'left')
RETURNS TABLE (period tgsis.timerange)
LANGUAGE plpgsql
STABLE
AS $$
DECLARE
    v_class tgsis.catalog := tgsis.checked_question(p_class, p_geoid, p_property, false, p_op, p_value, p_convention);
    v_pieces text;
BEGIN
    IF v_class.timemodel NOT IN ('INSTANTS', 'EVOLVING') THEN
        PERFORM tgsis.no_model_rule(v_class.timemodel, 'tgsis.property_periods', '{INSTANTS,EVOLVING}');
    END IF;
    IF v_class.timemodel = 'INSTANTS' THEN
        v_pieces := format($q$
            SELECT i.period AS r
              FROM tgsis.instant_periods($1, $4) i
              JOIN %I.%I p ON p._geoid = $1 AND p._times = i.times
             WHERE tgsis.satisfies(p.%I::double precision, $2, $3)
            $q$, v_class.schemaname, v_class.protablename, p_property);
    ELSE
        v_pieces := format($q$
            SELECT x.r
              FROM (SELECT i.*, p.%1$I::double precision AS a,
                           lead(p.%1$I::double precision) OVER (PARTITION BY i.timem ORDER BY i.timet) AS b
                      FROM tgsis.evolving_instants($1) i
                      LEFT JOIN %2$I.%3$I p ON p._geoid = $1 AND p._timem = i.timem AND p._timet = i.timet) s,
                   unnest(tgsis.evolving_satisfied(s.timem, s.next_timem, s.timet, s.t_next, s.a, s.b, s.hold, $2, $3)) x(r)
            $q$, p_property, v_class.schemaname, v_class.protablename);
    END IF;
    RETURN QUERY EXECUTE format('SELECT u.r::tgsis.timerange FROM (SELECT range_agg(p.r) AS m FROM (%s) p) a, unnest(a.m) u(r) ORDER BY 1',
                                v_pieces)
        USING p_geoid, p_op, p_value, p_convention;
END
$$;

COMMENT ON FUNCTION tgsis.property_periods(text, bigint, text, text, double precision, text) IS
    'maximal intervals of model time (tgsis.timerange) in which a numeric per-instant property of a feature satisfies property op value (op: <, <=, >, >=, =, <>): model 2 stepwise by the left- or right-closed convention, model 3 linear between geometry instants; NULL and NaN values never satisfy it';
