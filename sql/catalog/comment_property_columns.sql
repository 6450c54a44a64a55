-- tgsis.comment_property_columns(schema, table, properties, what): COMMENT ON each property column of a class table.
CREATE FUNCTION tgsis.comment_property_columns(p_schema text, p_table text, p_properties jsonb, p_what text)
RETURNS void
LANGUAGE plpgsql
VOLATILE
AS $$
DECLARE
    v_prop jsonb;
BEGIN
    FOR v_prop IN SELECT * FROM jsonb_array_elements(p_properties) LOOP
        EXECUTE format('COMMENT ON COLUMN %I.%I.%I IS %L', p_schema, p_table, v_prop ->> 'name',
                       format('%s (%s%s)', p_what, v_prop ->> 'type',
                              CASE WHEN v_prop ? 'size' THEN format('[%s]: a vector of %s components', v_prop ->> 'size', v_prop ->> 'size') ELSE '' END));
    END LOOP;
END
$$;

COMMENT ON FUNCTION tgsis.comment_property_columns(text, text, jsonb, text) IS
    'comment each property column ([{"name", "type"}]) of a feature-class table as "<what> (<type>)"';
