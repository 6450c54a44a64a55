-- tgsis.first_time(class, geoid, property, op, value, convention): for each vertex/node or cell of a feature, the first time at which its property satisfies "property op value"; cells that never do are left out.
-- The first time is the infimum of the times at which it holds; the condition
-- may hold only right after it. Model 2 (INSTANTS): the smallest lower bound of
-- the step intervals (tgsis.instant_periods) of the instants whose value
-- satisfies it: left-closed t_i itself; right-closed t_i-1 (the value of t_i
-- holds from right after t_i-1), t_0 for the first instant. Model 3
-- (EVOLVING): a node or triangle belongs to one topology period and its value
-- is linear between the period's geometry instants (tgsis.evolving_satisfied;
-- a missing sample makes the stretches next to it unknown); convention is not
-- used. NaN values are unknown. One set-based query.
CREATE FUNCTION tgsis.first_time(p_class text, p_geoid bigint, p_property text, p_op text,
                                 p_value double precision, p_convention text DEFAULT 'left')
RETURNS TABLE (idx bigint, t double precision)
LANGUAGE plpgsql
STABLE
AS $$
DECLARE
    v_class tgsis.catalog := tgsis.checked_question(p_class, p_geoid, p_property, true, p_op, p_value, p_convention);
    v_first text;
BEGIN
    IF v_class.timemodel NOT IN ('INSTANTS', 'EVOLVING') THEN
        PERFORM tgsis.no_model_rule(v_class.timemodel, 'tgsis.first_time', '{INSTANTS,EVOLVING}');
    END IF;
    IF v_class.timemodel = 'INSTANTS' THEN
        v_first := format($q$
            SELECT c._idx, min(lower(i.period))
              FROM %I.%I c
              JOIN tgsis.instant_periods($1, $4) i ON i.times = c._times
             WHERE c._geoid = $1 AND tgsis.satisfies(c.%I::double precision, $2, $3)
             GROUP BY c._idx
            $q$, v_class.schemaname, v_class.cellprotable, p_property);
    ELSE
        v_first := format($q$
            SELECT c._idx, min(lower(tgsis.evolving_satisfied(i.timem, i.next_timem, i.timet, i.t_next, c.a,
                                                             CASE WHEN c.c_next = i.t_next THEN c.b END, i.hold, $2, $3)))
              FROM (SELECT c._idx, c._timem, c._timet, c.%1$I::double precision AS a,
                           lead(c._timet) OVER w AS c_next, lead(c.%1$I::double precision) OVER w AS b
                      FROM %2$I.%3$I c
                     WHERE c._geoid = $1
                    WINDOW w AS (PARTITION BY c._idx, c._timem ORDER BY c._timet)) c
              JOIN tgsis.evolving_instants($1) i ON i.timem = c._timem AND i.timet = c._timet
             GROUP BY c._idx
            $q$, p_property, v_class.schemaname, v_class.cellprotable);
    END IF;
    RETURN QUERY EXECUTE format('SELECT f.* FROM (%s) f(idx, t) WHERE f.t IS NOT NULL ORDER BY f.idx', v_first)
        USING p_geoid, p_op, p_value, p_convention;
END
$$;

COMMENT ON FUNCTION tgsis.first_time(text, bigint, text, text, double precision, text) IS
    'for each vertex/node or cell of a feature, the first (infimum) model time at which a numeric cell property satisfies property op value: model 2 stepwise (left-closed t_i, right-closed t_i-1), model 3 linear between the geometry instants of its period; cells that never do are left out';
