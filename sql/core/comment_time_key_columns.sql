-- tgsis.comment_time_key_columns(schema, table, time model): COMMENT ON the time-key columns of a temporal class table.
CREATE FUNCTION tgsis.comment_time_key_columns(p_schema text, p_table text, p_time_model text)
RETURNS void
LANGUAGE plpgsql
VOLATILE
AS $$
BEGIN
    IF p_time_model = 'INSTANTS' THEN
        EXECUTE format('COMMENT ON COLUMN %I.%I._times IS %L', p_schema, p_table,
                       'instant (model time) the values belong to: one of tgsis.times of the feature');
    ELSIF p_time_model = 'EVOLVING' THEN
        EXECUTE format('COMMENT ON COLUMN %I.%I._timem IS %L', p_schema, p_table,
                       'topology period (its start, tgsis.timem) the values belong to');
        EXECUTE format('COMMENT ON COLUMN %I.%I._timet IS %L', p_schema, p_table,
                       'geometry instant (tgsis.timet of the period) the values belong to; values are linear in between');
    END IF;
END
$$;

COMMENT ON FUNCTION tgsis.comment_time_key_columns(text, text, text) IS
    'comment the _times (INSTANTS) or _timem, _timet (EVOLVING) columns of a temporal feature-class table';
