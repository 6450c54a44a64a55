-- tgsis.comment_time_key_columns(schema, table, time model): COMMENT ON the time-key columns of a temporal class table.
-- The comments are the data model's (tgsis.data_models.timekey).
CREATE FUNCTION tgsis.comment_time_key_columns(p_schema text, p_table text, p_time_model text)
RETURNS void
LANGUAGE plpgsql
VOLATILE
AS $$
DECLARE
    v_key jsonb;
BEGIN
    FOR v_key IN SELECT k FROM tgsis.data_models m, jsonb_array_elements(m.timekey) AS k
                  WHERE m.timemodel = upper(p_time_model) LOOP
        EXECUTE format('COMMENT ON COLUMN %I.%I.%I IS %L', p_schema, p_table, v_key ->> 'name', v_key ->> 'comment');
    END LOOP;
END
$$;

COMMENT ON FUNCTION tgsis.comment_time_key_columns(text, text, text) IS
    'comment the time-key columns (tgsis.data_models.timekey: _times of INSTANTS, _timem and _timet of EVOLVING) of a temporal feature-class table';
