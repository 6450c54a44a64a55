-- tgsis.drop_property(class, name, kind, force): remove a property of a feature class, in every version.
-- Its column goes from its table (from the storage <table>_ver when
-- versioned: every version loses it, table definitions are not versioned)
-- and from tgsis.catalog. While any row of any version holds a value of it
-- (not NULL), dropping would lose data: refused (TG202) unless p_force. Key
-- and time columns are no properties and are refused (TG101). Runs as
-- tgsis's owner (SECURITY DEFINER), for members of tgsis_admin.
CREATE FUNCTION tgsis.drop_property(p_class text, p_name text, p_kind text DEFAULT NULL, p_force boolean DEFAULT false)
RETURNS tgsis.catalog
LANGUAGE plpgsql
VOLATILE
SECURITY DEFINER
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_class  tgsis.catalog := tgsis.class_for_change(p_class, 'drop');
    v_prop   record;
    v_list   text;
    v_values bigint;
    v_row    tgsis.catalog;
BEGIN
    SELECT * INTO v_prop FROM tgsis.class_property(v_class, p_name, p_kind);
    EXECUTE format('SELECT count(*) FROM %s WHERE %I IS NOT NULL', tgsis.storage_table(v_class.schemaname, v_prop.tablename),
                   p_name)
       INTO v_values;
    IF v_values > 0 AND NOT coalesce(p_force, false) THEN
        RAISE EXCEPTION '% property % of feature class % holds % value(s)', v_prop.kind, quote_literal(p_name), p_class, v_values
            USING ERRCODE = 'TG202',
                  DETAIL = format('Rows of %s in every version count; dropping the property deletes its values.', v_prop.tablename),
                  HINT = 'drop it with p_force => true to delete its values';
    END IF;
    PERFORM tgsis.alter_class_table(v_class, v_prop.tablename, ARRAY[format('DROP COLUMN %I', p_name)]);
    v_list := CASE v_prop.kind WHEN 'feature' THEN 'feature_properties' WHEN 'cell' THEN 'cell_properties'
                               ELSE 'instant_properties' END;
    EXECUTE format('UPDATE tgsis.catalog c SET %I = coalesce((SELECT jsonb_agg(p ORDER BY i)
                                                                FROM jsonb_array_elements(c.%I) WITH ORDINALITY AS e (p, i)
                                                               WHERE p ->> ''name'' <> $2), ''[]'')
                     WHERE c.classname = $1 RETURNING *', v_list, v_list)
       INTO v_row USING p_class, p_name;
    RETURN v_row;
END
$$;

COMMENT ON FUNCTION tgsis.drop_property(text, text, text, boolean) IS
    'drop a property of a feature class (tgsis_admin members), in every version; refused (TG202) while a row of any version holds a value unless p_force; p_kind (feature, cell, instant) when the name is in more than one list; updates tgsis.catalog, the views and the versioning triggers; returns the catalog row';
