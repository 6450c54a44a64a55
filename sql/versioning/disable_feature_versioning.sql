-- tgsis.disable_feature_versioning(force): make model 1 and the feature-class tables plain again with DEFAULT's rows.
CREATE FUNCTION tgsis.disable_feature_versioning(p_force boolean DEFAULT false)
RETURNS bigint
LANGUAGE plpgsql
VOLATILE
SECURITY DEFINER
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_t       tgsis.versioned_tables;
    v_class   text;
    v_removed bigint := 0;
BEGIN
    FOR v_class IN SELECT classname FROM tgsis.catalog LOOP
        EXECUTE format('DROP VIEW IF EXISTS %I.%I', (SELECT schemaname FROM tgsis.catalog WHERE classname = v_class),
                       (SELECT viewname FROM tgsis.catalog WHERE classname = v_class));
    END LOOP;
    FOR v_t IN SELECT * FROM tgsis.versioned_tables
                WHERE objectclass = 'feature' OR (schemaname = 'tgsis' AND tablename IN (SELECT tablename FROM tgsis.model_tables))
                ORDER BY iudorder DESC, tablename LOOP
        v_removed := v_removed + tgsis.disable_versioning_rel(format('%I.%I', v_t.schemaname, v_t.tablename)::regclass, p_force);
    END LOOP;
    FOR v_class IN SELECT classname FROM tgsis.catalog ORDER BY classname LOOP
        PERFORM tgsis.create_class_view(v_class);
    END LOOP;
    RETURN v_removed;
END
$$;

REVOKE ALL ON FUNCTION tgsis.disable_feature_versioning(boolean) FROM PUBLIC;

COMMENT ON FUNCTION tgsis.disable_feature_versioning(boolean) IS
    'make tgsis.geometry, vrtx, simplices and feature-class tables plain again with the rows DEFAULT sees (see disable_versioning); returns the row versions removed';
