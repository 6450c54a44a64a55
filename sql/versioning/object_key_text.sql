-- tgsis.object_key_text(key): an object key of a type whose text depends on the session, as canonical text.
-- Versioning turns object keys into text (advisory lock keys, tgsis.object_locks,
-- tgsis.revision_objects, tgsis.conflicts, diffs) and compares them as text;
-- the text a type's cast to text gives depends for some types on the
-- session's DateStyle, TimeZone, IntervalStyle, extra_float_digits or
-- bytea_output, so that two sessions would name one object two ways (an
-- edit under DateStyle 'SQL, DMY' wrote through another version's lock and
-- was lost by its merge). These overloads give one text per key whatever
-- the session's settings, and one text for values the key column's equality
-- holds equal (a primary key holds them to be one key): ISO dates, times in
-- UTC, shortest round-trip floats with -0 as 0, numerics without trailing
-- zeros, intervals with months as 30 days and days as 24 hours, bytea in hex.
-- Each text reads back as the same value under any setting
-- (tgsis.object_key_sql says which types take which form). Functions are
-- schema-qualified and literals escape-free: bodies of SQL functions are
-- parsed with the caller's settings. Without SET clauses where possible, so
-- that the planner inlines them (the views' write triggers call them per row).
CREATE FUNCTION tgsis.object_key_text(p_key timestamp)
RETURNS text
LANGUAGE sql
STABLE
PARALLEL SAFE
AS $$
    SELECT CASE WHEN NOT pg_catalog.isfinite(p_key) THEN pg_catalog.textin(pg_catalog.timestamp_out(p_key))
                ELSE pg_catalog.to_char(p_key, 'YYYY-MM-DD HH24:MI:SS')
                     OPERATOR(pg_catalog.||) pg_catalog.rtrim(pg_catalog.rtrim(pg_catalog.to_char(p_key, '.US'), '0'), '.')
                     OPERATOR(pg_catalog.||) CASE WHEN pg_catalog.to_char(p_key, 'BC') OPERATOR(pg_catalog.=) 'BC' THEN ' BC' ELSE '' END END
$$;

CREATE FUNCTION tgsis.object_key_text(p_key timestamptz)
RETURNS text
LANGUAGE sql
STABLE
PARALLEL SAFE
AS $$
    SELECT CASE WHEN NOT pg_catalog.isfinite(p_key) THEN pg_catalog.textin(pg_catalog.timestamptz_out(p_key))
                ELSE pg_catalog.to_char(pg_catalog.timezone('UTC', p_key), 'YYYY-MM-DD HH24:MI:SS')
                     OPERATOR(pg_catalog.||) pg_catalog.rtrim(pg_catalog.rtrim(pg_catalog.to_char(pg_catalog.timezone('UTC', p_key), '.US'), '0'), '.')
                     OPERATOR(pg_catalog.||) '+00'
                     OPERATOR(pg_catalog.||) CASE WHEN pg_catalog.to_char(pg_catalog.timezone('UTC', p_key), 'BC') OPERATOR(pg_catalog.=) 'BC'
                                             THEN ' BC' ELSE '' END END
$$;

CREATE FUNCTION tgsis.object_key_text(p_key date)
RETURNS text
LANGUAGE sql
STABLE
PARALLEL SAFE
AS $$
    SELECT CASE WHEN NOT pg_catalog.isfinite(p_key) THEN pg_catalog.textin(pg_catalog.date_out(p_key))
                ELSE pg_catalog.to_char(p_key::timestamp, 'YYYY-MM-DD')
                     OPERATOR(pg_catalog.||) CASE WHEN pg_catalog.to_char(p_key::timestamp, 'BC') OPERATOR(pg_catalog.=) 'BC'
                                             THEN ' BC' ELSE '' END END
$$;

CREATE FUNCTION tgsis.object_key_text(p_key float8)
RETURNS text
LANGUAGE sql
IMMUTABLE
PARALLEL SAFE
SET extra_float_digits = 1
AS $$
    SELECT CASE WHEN p_key OPERATOR(pg_catalog.=) 0::pg_catalog.float8 THEN '0' ELSE pg_catalog.textin(pg_catalog.float8out(p_key)) END
$$;

CREATE FUNCTION tgsis.object_key_text(p_key float4)
RETURNS text
LANGUAGE sql
IMMUTABLE
PARALLEL SAFE
SET extra_float_digits = 1
AS $$
    SELECT CASE WHEN p_key OPERATOR(pg_catalog.=) 0::pg_catalog.float4 THEN '0' ELSE pg_catalog.textin(pg_catalog.float4out(p_key)) END
$$;

CREATE FUNCTION tgsis.object_key_text(p_key numeric)
RETURNS text
LANGUAGE sql
IMMUTABLE
PARALLEL SAFE
AS $$
    SELECT pg_catalog.textin(pg_catalog.numeric_out(pg_catalog.trim_scale(p_key)))
$$;

-- months count 30 days and days 24 hours, as the interval's equality counts
-- them ('1 mon' = '30 days'); the text has days and time of one sign, each
-- signed, so that IntervalStyle sql_standard reads it back the same
CREATE FUNCTION tgsis.object_key_text(p_key interval)
RETURNS text
LANGUAGE sql
IMMUTABLE
PARALLEL SAFE
SET IntervalStyle = 'postgres'
AS $$
    SELECT CASE WHEN NOT pg_catalog.isfinite(p_key) THEN pg_catalog.textin(pg_catalog.interval_out(p_key))
                ELSE pg_catalog.textin(pg_catalog.interval_out(pg_catalog.justify_hours(
                         p_key OPERATOR(pg_catalog.-) pg_catalog.make_interval(months => m.n)
                               OPERATOR(pg_catalog.+) pg_catalog.make_interval(days => m.n OPERATOR(pg_catalog.*) 30)))) END
      FROM (SELECT (pg_catalog.date_part('year', p_key) OPERATOR(pg_catalog.*) 12
                    OPERATOR(pg_catalog.+) pg_catalog.date_part('month', p_key))::integer AS n) AS m
$$;

CREATE FUNCTION tgsis.object_key_text(p_key bytea)
RETURNS text
LANGUAGE sql
IMMUTABLE
PARALLEL SAFE
AS $$
    SELECT E'\\x' OPERATOR(pg_catalog.||) pg_catalog.encode(p_key, 'hex')
$$;

COMMENT ON FUNCTION tgsis.object_key_text(timestamp) IS
    'canonical text of a timestamp object key: ISO (YYYY-MM-DD HH24:MI:SS[.ffffff][ BC]) whatever the session''s DateStyle';
COMMENT ON FUNCTION tgsis.object_key_text(timestamptz) IS
    'canonical text of a timestamptz object key: ISO in UTC (YYYY-MM-DD HH24:MI:SS[.ffffff]+00[ BC]) whatever the session''s DateStyle and TimeZone';
COMMENT ON FUNCTION tgsis.object_key_text(date) IS
    'canonical text of a date object key: ISO (YYYY-MM-DD[ BC]) whatever the session''s DateStyle';
COMMENT ON FUNCTION tgsis.object_key_text(float8) IS
    'canonical text of a float8 object key: the shortest text that reads back exactly, -0 as 0, whatever extra_float_digits';
COMMENT ON FUNCTION tgsis.object_key_text(float4) IS
    'canonical text of a float4 object key: the shortest text that reads back exactly, -0 as 0, whatever extra_float_digits';
COMMENT ON FUNCTION tgsis.object_key_text(numeric) IS
    'canonical text of a numeric object key: without trailing zeros (1.0 and 1.00 are one key)';
COMMENT ON FUNCTION tgsis.object_key_text(interval) IS
    'canonical text of an interval object key: days (months as 30) and time of one sign (IntervalStyle postgres), equal intervals one text';
COMMENT ON FUNCTION tgsis.object_key_text(bytea) IS
    'canonical text of a bytea object key: hex (\x...) whatever bytea_output';
