-- tgsis.rename_property(class, name, new name, kind): rename a property of a feature class, in every version.
-- The column is renamed in its table (in the storage <table>_ver when
-- versioned, so that every row version of every version keeps its values
-- under the new name) and in tgsis.catalog; its comment goes with it. The new
-- name follows the rules of register_feature_class; p_kind ('feature',
-- 'cell', 'instant') says which property is meant when the name is in more
-- than one list. Runs as tgsis's owner (SECURITY DEFINER), for members of
-- tgsis_admin.
CREATE FUNCTION tgsis.rename_property(p_class text, p_name text, p_new_name text, p_kind text DEFAULT NULL)
RETURNS tgsis.catalog
LANGUAGE plpgsql
VOLATILE
SECURITY DEFINER
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_class tgsis.catalog := tgsis.class_for_change(p_class, 'rename');
    v_prop  record;
    v_new   text;
    v_list  text;
    v_row   tgsis.catalog;
BEGIN
    SELECT * INTO v_prop FROM tgsis.class_property(v_class, p_name, p_kind);
    -- the new name as a property list would take it (letters, digits, underscores; TG101 otherwise)
    SELECT c.name INTO v_new FROM tgsis.property_columns(jsonb_build_array(jsonb_build_array(p_new_name, v_prop.item ->> 'type')),
                                                         false, v_prop.kind) c;
    IF v_new IN ('revision', 'lastrevs', 'revclosed')
       OR (v_prop.kind = 'feature' AND v_new IN ('geoname', 'geotype', 'nvrtx', 'ncell', 'bbox', 'created_at'))
       OR (v_prop.kind = 'cell' AND v_new = 'part') THEN
        RAISE EXCEPTION '% property name % is taken by tgsis', v_prop.kind, quote_literal(v_new)
            USING ERRCODE = 'TG101',
                  DETAIL = CASE WHEN v_new = 'part'
                                THEN 'A cell property "part" holds the parts of features stored in tgsis.part otherwise; only a class registered with it stores them there.'
                                WHEN v_new IN ('revision', 'lastrevs', 'revclosed')
                                THEN 'Versioning adds the columns revision, lastrevs and revclosed.'
                                ELSE format('The class view %s has a column of that name from tgsis.geometry.', v_class.viewname) END,
                  HINT = 'choose another name';
    END IF;
    v_list := CASE v_prop.kind WHEN 'feature' THEN 'feature_properties' WHEN 'cell' THEN 'cell_properties'
                               ELSE 'instant_properties' END;
    -- (the names of both alignments share one list: they are unique within it, as at registration)
    IF v_new <> p_name AND EXISTS (
           SELECT FROM jsonb_array_elements(CASE v_prop.kind WHEN 'feature' THEN v_class.feature_properties
                                                             WHEN 'cell' THEN v_class.cell_properties
                                                             ELSE v_class.instant_properties END) p
            WHERE p ->> 'name' = v_new) THEN
        RAISE EXCEPTION 'feature class % has a % property % already', p_class, v_prop.kind, quote_literal(v_new)
            USING ERRCODE = 'TG201', HINT = 'choose another name, or drop the existing property first';
    END IF;
    IF v_new = p_name THEN
        RETURN v_class;
    END IF;
    PERFORM tgsis.alter_class_table(v_class, v_prop.tablename, ARRAY[format('RENAME COLUMN %I TO %I', p_name, v_new)]);
    EXECUTE format('UPDATE tgsis.catalog c SET %I = (SELECT jsonb_agg(CASE WHEN p ->> ''name'' = $2 THEN jsonb_set(p, ''{name}'', to_jsonb($3))
                                                                         ELSE p END ORDER BY i)
                                                      FROM jsonb_array_elements(c.%I) WITH ORDINALITY AS e (p, i))
                     WHERE c.classname = $1 RETURNING *', v_list, v_list)
       INTO v_row USING p_class, p_name, v_new;
    RETURN v_row;
END
$$;

COMMENT ON FUNCTION tgsis.rename_property(text, text, text, text) IS
    'rename a property of a feature class (tgsis_admin members), in every version (its values kept in every row version); p_kind (feature, cell, instant) when the name is in more than one list; updates tgsis.catalog, the views and the versioning triggers; returns the catalog row';
