-- tgsis.time_key_columns(time model): the time-key columns a class table of that model has between _geoid and the rest.
CREATE FUNCTION tgsis.time_key_columns(p_time_model text)
RETURNS text
LANGUAGE sql
IMMUTABLE
PARALLEL SAFE
AS $$
    SELECT CASE p_time_model WHEN 'INSTANTS' THEN '_times, ' WHEN 'EVOLVING' THEN '_timem, _timet, ' ELSE '' END
$$;

COMMENT ON FUNCTION tgsis.time_key_columns(text) IS
    'time-key column list ending in ", " of the class tables of a time model: '''' (STATIC), ''_times, '' (INSTANTS), ''_timem, _timet, '' (EVOLVING)';
