-- tgsis.property_rows_missing(class, table): the stored geometries of a class that should have rows in one of its vertex or cell property tables and have none.
-- A class registered without vertex or cell properties stores no rows in its
-- property tables (an upload writes them only for properties it has). Once a
-- property is added, the readers expect one row per vertex (or cell) of every
-- feature, and of every collection member that has all the class's
-- properties (a member that lacks some lists those it has in its metadata,
-- key tgsis_properties). This finds those with no row at all, across every
-- version and revision (the storage, <table>_ver when versioned): what
-- tgsis.add_property and tgsis.fill_property_rows give rows. Runs as its
-- callers (tgsis's owner).
CREATE FUNCTION tgsis.property_rows_missing(p_class tgsis.catalog, p_table text)
RETURNS bigint[]
LANGUAGE plpgsql
STABLE
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_feature  text := tgsis.storage_table(p_class.schemaname, p_class.featuretable);
    v_props    text := tgsis.storage_table(p_class.schemaname, p_table);
    v_geometry text := tgsis.storage_table('tgsis', 'geometry');
    v_geoids   bigint[];
BEGIN
    IF p_class.geotype = 'GEOMETRYCOLLECTION' THEN
        EXECUTE format(
            'SELECT array_agg(DISTINCT m.geoid ORDER BY m.geoid)
               FROM %1$s f JOIN %2$s g ON g.geoid = f._geoid CROSS JOIN LATERAL unnest(g.geoids) AS m(geoid)
              WHERE NOT EXISTS (SELECT FROM %2$s mg WHERE mg.geoid = m.geoid AND mg.metadata ? ''tgsis_properties'')
                AND NOT EXISTS (SELECT FROM %3$s p WHERE p._geoid = m.geoid)', v_feature, v_geometry, v_props)
           INTO v_geoids;
    ELSE
        EXECUTE format(
            'SELECT array_agg(DISTINCT f._geoid ORDER BY f._geoid) FROM %1$s f
              WHERE NOT EXISTS (SELECT FROM %2$s p WHERE p._geoid = f._geoid)', v_feature, v_props)
           INTO v_geoids;
    END IF;
    RETURN coalesce(v_geoids, '{}');
END
$$;

COMMENT ON FUNCTION tgsis.property_rows_missing(tgsis.catalog, text) IS
    'geometries (features, or collection members that have all the class''s properties) of a class with no row at all in one of its vertex or cell property tables, in any version (its storage); used by add_property and fill_property_rows';
