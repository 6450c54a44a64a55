-- tgsis.timerange: an interval of model time (double precision), for the
-- answers of the temporal questions (tgsis.property_periods). Bounds may be
-- open or closed, '[t, t]' is a single instant, and an unbounded end ('[t,)')
-- means for ever (an alive feature after its last instant). The multirange
-- type tgsis.timemultirange comes with it; range_agg merges overlapping and
-- adjacent intervals ('[1,2)' and '[2,3]' give '[1,3]', '(1,2)' and '(2,3)' stay two).
--
-- Why a domain over a range type rather than the range type itself: NaN is no
-- model time, but PostgreSQL's float8 ranges take it as a number above every
-- other ('[1,NaN)' was everything from 1 on) and its constructor refuses
-- timerange('NaN', 1) with a raw 22000 about bound order. A range type can
-- only refuse values in a C canonical function; a domain's CHECK refuses them
-- in SQL, and the constructor tgsis.timerange(lower, upper[, bounds]) is then
-- tgsis's own, which names the bad bound (TG100). The range type under it,
-- tgsis.modeltime_range, is what PostgreSQL's range operators and functions
-- work on: @>, <@, &&, lower(), upper(), range_agg take the domain as their
-- base type and give double precision, tgsis.timemultirange and (for * + -)
-- tgsis.modeltime_range; it reaches clients as that type's oid (a domain is
-- sent as its base type). tgsis's own code builds its ranges with
-- tgsis.modeltime_range(...) (never NaN: tgsis.invalid_period guards) and
-- returns them as tgsis.timerange.
-- The constructors of tgsis.modeltime_range and tgsis.timemultirange belong to
-- the bootstrap superuser whoever runs this, so an installer that is not a
-- superuser could not comment on them: the type comments document them.
CREATE TYPE tgsis.modeltime_range AS RANGE (
    subtype              = double precision,
    subtype_diff         = float8mi,
    multirange_type_name = tgsis.timemultirange
);

COMMENT ON TYPE tgsis.modeltime_range IS
    'range of double precision under tgsis.timerange (which refuses NaN bounds): what range operators on tgsis.timerange values work on and give back for * + -; made by tgsis.modeltime_range(lower, upper, ''[)'')';
COMMENT ON TYPE tgsis.timemultirange IS
    'set of disjoint intervals of model time (multirange of tgsis.modeltime_range, the range under tgsis.timerange), made by tgsis.timemultirange(range, ...) which merges overlapping and adjacent ones';

-- the domain's check: a function, so that a NaN bound is refused with tgsis's code and the bound named
CREATE FUNCTION tgsis.timerange_bounds_ok(p_period tgsis.modeltime_range)
RETURNS boolean
LANGUAGE plpgsql
IMMUTABLE
PARALLEL SAFE
AS $$
BEGIN
    IF pg_catalog.lower(p_period) = 'NaN'::double precision OR pg_catalog.upper(p_period) = 'NaN'::double precision THEN
        RAISE EXCEPTION 'NaN is no bound of a period of model time: %', p_period
            USING ERRCODE = 'TG100',
                  DETAIL = format('The %s bound is NaN; NaN sorts above every number, so the period would mean something else.',
                                  CASE WHEN pg_catalog.lower(p_period) = 'NaN'::double precision THEN 'lower' ELSE 'upper' END),
                  HINT = 'give numbers; -Infinity and Infinity are allowed, and a NULL bound is unbounded';
    END IF;
    RETURN true;
END
$$;

COMMENT ON FUNCTION tgsis.timerange_bounds_ok(tgsis.modeltime_range) IS
    'the check of the domain tgsis.timerange: true, or TG100 naming a NaN bound';

CREATE DOMAIN tgsis.timerange AS tgsis.modeltime_range
    CONSTRAINT timerange_bounds_are_numbers CHECK (tgsis.timerange_bounds_ok(VALUE));

COMMENT ON DOMAIN tgsis.timerange IS
    'interval of model time (double precision) with open or closed bounds, made by tgsis.timerange(lower, upper, ''[)'') (NULL bound: unbounded; unbounded upper end: for ever; NaN refused)';

-- the constructors: PostgreSQL's, with the bad arguments named first (TG100)
CREATE FUNCTION tgsis.timerange(p_lower double precision, p_upper double precision, p_bounds text)
RETURNS tgsis.timerange
LANGUAGE plpgsql
IMMUTABLE
PARALLEL SAFE
AS $$
BEGIN
    IF p_lower = 'NaN'::double precision OR p_upper = 'NaN'::double precision THEN
        RAISE EXCEPTION 'NaN is no bound of a period of model time: tgsis.timerange(%, %)', p_lower, p_upper
            USING ERRCODE = 'TG100',
                  DETAIL = format('The %s bound is NaN; NaN sorts above every number, so the period would mean something else.',
                                  CASE WHEN p_lower = 'NaN'::double precision THEN 'lower' ELSE 'upper' END),
                  HINT = 'give numbers; -Infinity and Infinity are allowed, and a NULL bound is unbounded';
    END IF;
    IF p_lower > p_upper THEN
        RAISE EXCEPTION 'the lower bound % of a period of model time is after its upper bound %', p_lower, p_upper
            USING ERRCODE = 'TG100',
                  HINT = 'give the earlier time first';
    END IF;
    IF p_bounds IS NULL OR p_bounds NOT IN ('[)', '(]', '()', '[]') THEN
        RAISE EXCEPTION 'bounds % of a period of model time are none of [), (], () and []',
                        coalesce(quote_literal(pg_catalog.left(p_bounds, 20)), 'NULL')
            USING ERRCODE = 'TG100',
                  HINT = 'give ''[)'' (the default), ''(]'', ''()'' or ''[]''';
    END IF;
    RETURN tgsis.modeltime_range(p_lower, p_upper, p_bounds);
END
$$;

CREATE FUNCTION tgsis.timerange(p_lower double precision, p_upper double precision)
RETURNS tgsis.timerange
LANGUAGE sql
IMMUTABLE
PARALLEL SAFE
AS $$
    SELECT tgsis.timerange(p_lower, p_upper, '[)')
$$;

COMMENT ON FUNCTION tgsis.timerange(double precision, double precision, text) IS
    'the period of model time from p_lower to p_upper with bounds p_bounds (''[)'', ''(]'', ''()'' or ''[]''); a NULL bound is unbounded; TG100 for NaN, a lower bound after the upper or unknown bounds';
COMMENT ON FUNCTION tgsis.timerange(double precision, double precision) IS
    'the period of model time [p_lower, p_upper); a NULL bound is unbounded; TG100 for NaN or a lower bound after the upper';
