-- tgsis.time_key_columns(time model): the time-key columns a class table of that model has between _geoid and the rest.
-- From the data model's registry row (tgsis.data_models.timekey).
CREATE FUNCTION tgsis.time_key_columns(p_time_model text)
RETURNS text
LANGUAGE sql
STABLE
PARALLEL SAFE
AS $$
    SELECT coalesce((SELECT string_agg(quote_ident(k ->> 'name') || ', ', '' ORDER BY i)
                       FROM tgsis.data_models m, jsonb_array_elements(m.timekey) WITH ORDINALITY AS e (k, i)
                      WHERE m.timemodel = upper(p_time_model)), '')
$$;

COMMENT ON FUNCTION tgsis.time_key_columns(text) IS
    'time-key column list ending in ", " of the class tables of a time model (tgsis.data_models.timekey): '''' (STATIC), ''_times, '' (INSTANTS), ''_timem, _timet, '' (EVOLVING)';
