-- tgsis.invalid_period(names, t0, t1): raise TG100 for two model times that are no period (NaN, or the first after the second).
-- The interval helpers (tgsis.linear_satisfied, tgsis.evolving_satisfied)
-- are SQL functions that the planner inlines into the temporal questions;
-- they call this only in the CASE branch of bad arguments, so the good case
-- costs two comparisons and NaN never reaches a tgsis.timerange (where it
-- made a range '[0,NaN)', or PostgreSQL's raw 22000 for a reversed one).
CREATE FUNCTION tgsis.invalid_period(p_names text, p_t0 double precision, p_t1 double precision)
RETURNS tgsis.timemultirange
LANGUAGE plpgsql
IMMUTABLE
PARALLEL SAFE
AS $$
BEGIN
    RAISE EXCEPTION '% = % and % are no period of model time', p_names, p_t0, p_t1
        USING ERRCODE = 'TG100',
              DETAIL = 'A period needs two numbers (not NaN), the first not after the second.',
              HINT = format('give %s in order; -Infinity and Infinity are allowed', p_names);
END
$$;

COMMENT ON FUNCTION tgsis.invalid_period(text, double precision, double precision) IS
    'raise TG100 naming the arguments p_names whose model times t0, t1 are no period (NaN, or t0 after t1); used by the interval helpers of the temporal questions';
