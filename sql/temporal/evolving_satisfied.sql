-- tgsis.evolving_satisfied(timem, next_timem, t, t_next, a, b, hold, op, v): the times from model-3 geometry instant t up to the next one at which "value op v" holds.
-- The arguments but a, b, op and v are a row of tgsis.evolving_instants. The
-- value a at t holds at t itself; from t to t_next (the next geometry
-- instant of the period, value b there) the value is linear
-- (tgsis.linear_satisfied); after the period's last instant (t_next NULL) a
-- holds for ever when hold is true (a later period follows, or the feature
-- is alive). All of it is cut to the period's time [timem, next_timem): at a
-- topology change the new period applies. NULL or NaN values are unknown.
CREATE FUNCTION tgsis.evolving_satisfied(p_timem double precision, p_next_timem double precision, p_t double precision,
                                         p_t_next double precision, p_a double precision, p_b double precision,
                                         p_hold boolean, p_op text, p_v double precision)
RETURNS tgsis.timemultirange
LANGUAGE sql
IMMUTABLE
PARALLEL SAFE
AS $$
    SELECT CASE WHEN p_timem = 'NaN' OR p_next_timem = 'NaN' OR p_timem > p_next_timem
                THEN tgsis.invalid_period('p_timem, p_next_timem', p_timem, p_next_timem)
                WHEN p_t = 'NaN'
                THEN tgsis.invalid_period('p_timem, p_t', p_timem, p_t)
           ELSE (tgsis.timemultirange(CASE WHEN tgsis.satisfies(p_a, p_op, p_v)
                                      THEN tgsis.modeltime_range(p_t, CASE WHEN p_t_next IS NULL AND p_hold THEN NULL ELSE p_t END, '[]')
                                      ELSE 'empty' END)
            + tgsis.linear_satisfied(p_t, p_t_next, p_a, p_b, p_op, p_v))
           * tgsis.timemultirange(tgsis.modeltime_range(p_timem, p_next_timem, '[)')) END
$$;

COMMENT ON FUNCTION tgsis.evolving_satisfied(double precision, double precision, double precision, double precision, double precision, double precision, boolean, text, double precision) IS
    'model 3: the times in [t, t_next) (after the last instant of a period: [t, next period) or for ever if hold) at which a value a at t, linear to b at t_next, satisfies value op v; cut to the period [timem, next_timem)';
