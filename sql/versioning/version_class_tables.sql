-- tgsis.version_class_tables(class): version a feature class's two tables as part of object class 'feature'.
CREATE FUNCTION tgsis.version_class_tables(p_class text)
RETURNS void
LANGUAGE plpgsql
VOLATILE
AS $$
DECLARE
    v_class tgsis.catalog := tgsis.catalog_row(p_class);
BEGIN
    EXECUTE format('DROP VIEW IF EXISTS %I.%I', v_class.schemaname, v_class.viewname);  -- re-created over the versioned views
    IF NOT EXISTS (SELECT FROM tgsis.versioned_tables WHERE schemaname = v_class.schemaname AND tablename = v_class.featuretable) THEN
        PERFORM tgsis.enable_versioning_rel(format('%I.%I', v_class.schemaname, v_class.featuretable)::regclass,
                                            '_geoid', 'feature', 3, v_class.schemaname || '.' || v_class.featuretable);
    END IF;
    IF NOT EXISTS (SELECT FROM tgsis.versioned_tables WHERE schemaname = v_class.schemaname AND tablename = v_class.cellprotable) THEN
        PERFORM tgsis.enable_versioning_rel(format('%I.%I', v_class.schemaname, v_class.cellprotable)::regclass,
                                            '_geoid', 'feature', 4, v_class.schemaname || '.' || v_class.cellprotable);
    END IF;
    IF v_class.otherprotable IS NOT NULL
       AND NOT EXISTS (SELECT FROM tgsis.versioned_tables WHERE schemaname = v_class.schemaname AND tablename = v_class.otherprotable) THEN
        PERFORM tgsis.enable_versioning_rel(format('%I.%I', v_class.schemaname, v_class.otherprotable)::regclass,
                                            '_geoid', 'feature', 4, v_class.schemaname || '.' || v_class.otherprotable);
    END IF;
    IF v_class.protablename IS NOT NULL
       AND NOT EXISTS (SELECT FROM tgsis.versioned_tables WHERE schemaname = v_class.schemaname AND tablename = v_class.protablename) THEN
        PERFORM tgsis.enable_versioning_rel(format('%I.%I', v_class.schemaname, v_class.protablename)::regclass,
                                            '_geoid', 'feature', 4, v_class.schemaname || '.' || v_class.protablename);
    END IF;
END
$$;

COMMENT ON FUNCTION tgsis.version_class_tables(text) IS
    'version the feature, cell-property (both alignments) and per-instant property tables of a feature class (object class ''feature'', keyed by _geoid); drops <class>_v for the caller to re-create';
