-- tgsis.crossing_time(t0, t1, a, b, v): where a value going linearly from a at t0 to b at t1 equals v, t0 + (v - a) / (b - a) (t1 - t0), kept inside [t0, t1].
-- For a <> b and v between them; rounding may land it on t0 or t1.
CREATE FUNCTION tgsis.crossing_time(p_t0 double precision, p_t1 double precision, p_a double precision,
                                    p_b double precision, p_v double precision)
RETURNS double precision
LANGUAGE sql
IMMUTABLE
PARALLEL SAFE
AS $$
    SELECT greatest(p_t0, least(p_t1, p_t0 + (p_v - p_a) / (p_b - p_a) * (p_t1 - p_t0)))
$$;

COMMENT ON FUNCTION tgsis.crossing_time(double precision, double precision, double precision, double precision, double precision) IS
    'time in [t0, t1] at which a value linear from a (at t0) to b (at t1) equals v: t0 + (v - a)/(b - a) (t1 - t0), clamped; for a <> b with v between them';
