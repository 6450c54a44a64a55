-- tgsis.timerange: an interval of model time (double precision), for the
-- answers of the temporal questions (tgsis.property_periods). Bounds may be
-- open or closed, '[t, t]' is a single instant, and an unbounded end ('[t,)')
-- means for ever (an alive feature after its last instant). The multirange
-- type tgsis.timemultirange comes with it; range_agg merges overlapping and
-- adjacent intervals ('[1,2)' and '[2,3]' give '[1,3]', '(1,2)' and '(2,3)' stay two).
-- Its constructor functions tgsis.timerange(lower, upper[, bounds]) and
-- tgsis.timemultirange(...) belong to the bootstrap superuser whoever runs
-- this, so an installer that is not a superuser could not comment on them:
-- the type comments document them.
CREATE TYPE tgsis.timerange AS RANGE (
    subtype              = double precision,
    subtype_diff         = float8mi,
    multirange_type_name = tgsis.timemultirange
);

COMMENT ON TYPE tgsis.timerange IS
    'interval of model time (double precision) with open or closed bounds, made by tgsis.timerange(lower, upper, ''[)'') (NULL bound: unbounded; unbounded upper end: for ever)';
COMMENT ON TYPE tgsis.timemultirange IS
    'set of disjoint intervals of model time (multirange of tgsis.timerange), made by tgsis.timemultirange(range, ...) which merges overlapping and adjacent ones';
