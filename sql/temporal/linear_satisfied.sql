-- tgsis.linear_satisfied(t0, t1, a, b, op, v): the times inside the open interval (t0, t1) at which a value going linearly from a (at t0) to b (at t1) satisfies "value op v".
-- Where the value crosses v strictly inside, at tc = tgsis.crossing_time, the
-- pieces are (t0, tc), [tc, tc] and (tc, t1), each kept when the sign of
-- value - v there satisfies op (strict operators leave tc out, non-strict
-- ones keep it). Otherwise value - v has one sign on the whole open interval
-- (0 only when a = b = v). Unknown (empty) when a or b is NULL, NaN or
-- infinite, or when there is no t1.
CREATE FUNCTION tgsis.linear_satisfied(p_t0 double precision, p_t1 double precision, p_a double precision,
                                       p_b double precision, p_op text, p_v double precision)
RETURNS tgsis.timemultirange
LANGUAGE sql
IMMUTABLE
PARALLEL SAFE
AS $$
    SELECT CASE
               WHEN p_t0 = 'NaN' OR p_t1 = 'NaN' OR p_t0 > p_t1
                   THEN tgsis.invalid_period('p_t0, p_t1', p_t0, p_t1)
               WHEN p_t1 IS NULL
                    OR NOT coalesce(p_a > '-Infinity' AND p_a < 'Infinity' AND p_b > '-Infinity' AND p_b < 'Infinity', false)
                   THEN tgsis.timemultirange()
               WHEN least(p_a, p_b) < p_v AND p_v < greatest(p_a, p_b)
                   THEN tgsis.timemultirange(
                            CASE WHEN tgsis.satisfies(sign(p_a - p_v), p_op, 0)
                                 THEN tgsis.modeltime_range(p_t0, tgsis.crossing_time(p_t0, p_t1, p_a, p_b, p_v), '()')
                                 ELSE 'empty' END,
                            CASE WHEN tgsis.satisfies(0, p_op, 0)
                                 THEN tgsis.modeltime_range(tgsis.crossing_time(p_t0, p_t1, p_a, p_b, p_v),
                                                      tgsis.crossing_time(p_t0, p_t1, p_a, p_b, p_v), '[]')
                                 ELSE 'empty' END,
                            CASE WHEN tgsis.satisfies(sign(p_b - p_v), p_op, 0)
                                 THEN tgsis.modeltime_range(tgsis.crossing_time(p_t0, p_t1, p_a, p_b, p_v), p_t1, '()')
                                 ELSE 'empty' END)
                        * tgsis.timemultirange(tgsis.modeltime_range(p_t0, p_t1, '()'))
               WHEN tgsis.satisfies(sign(sign(p_a - p_v) + sign(p_b - p_v)), p_op, 0)
                   THEN tgsis.timemultirange(tgsis.modeltime_range(p_t0, p_t1, '()'))
               ELSE tgsis.timemultirange()
           END
$$;

COMMENT ON FUNCTION tgsis.linear_satisfied(double precision, double precision, double precision, double precision, text, double precision) IS
    'the times in the open interval (t0, t1) at which a value linear from a (at t0) to b (at t1) satisfies value op v, crossings by linear interpolation; empty when a or b is NULL or not finite';
