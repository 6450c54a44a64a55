-- tgsis.create_class_view(class): (re)create the view <class>_v joining a class's features with their geometry rows.
CREATE FUNCTION tgsis.create_class_view(p_class text)
RETURNS void
LANGUAGE plpgsql
VOLATILE
AS $$
DECLARE
    v_class  tgsis.catalog := tgsis.catalog_row(p_class);
    v_column record;
BEGIN
    EXECUTE format('DROP VIEW IF EXISTS %I.%I', v_class.schemaname, v_class.viewname);
    EXECUTE format('CREATE VIEW %I.%I AS SELECT g.geoname, f.*, g.geotype, g.nvrtx, g.ncell, g.bbox, g.created_at
                      FROM %I.%I f JOIN tgsis.geometry g ON g.geoid = f._geoid',
                   v_class.schemaname, v_class.viewname, v_class.schemaname, v_class.featuretable);
    EXECUTE format('COMMENT ON VIEW %I.%I IS %L', v_class.schemaname, v_class.viewname,
                   format('tgsis feature class %s: features with their name, geotype, counts and bounding box', p_class));
    -- the view's columns mean what they mean in the feature table and tgsis.geometry
    EXECUTE format('COMMENT ON COLUMN %I.%I.geoname IS %L', v_class.schemaname, v_class.viewname, 'name of the feature''s geometry');
    FOR v_column IN
        SELECT a.attname, coalesce(col_description(format('%I.%I', v_class.schemaname, v_class.featuretable)::regclass, f.attnum),
                                   col_description('tgsis.geometry'::regclass, g.attnum)) AS note
          FROM pg_catalog.pg_attribute a
          LEFT JOIN pg_catalog.pg_attribute f ON f.attrelid = format('%I.%I', v_class.schemaname, v_class.featuretable)::regclass
                                              AND f.attname = a.attname
          LEFT JOIN pg_catalog.pg_attribute g ON g.attrelid = 'tgsis.geometry'::regclass AND g.attname = a.attname
         WHERE a.attrelid = format('%I.%I', v_class.schemaname, v_class.viewname)::regclass AND a.attnum > 0
           AND a.attname <> 'geoname'
    LOOP
        EXECUTE format('COMMENT ON COLUMN %I.%I.%I IS %L', v_class.schemaname, v_class.viewname, v_column.attname, v_column.note);
    END LOOP;
    EXECUTE format('GRANT SELECT ON %I.%I TO tgsis_reader', v_class.schemaname, v_class.viewname);
END
$$;

COMMENT ON FUNCTION tgsis.create_class_view(text) IS
    '(re)create <class>_v: the class''s features joined with tgsis.geometry (name, geotype, counts, bbox), for psql users';
