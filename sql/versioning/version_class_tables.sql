-- tgsis.version_class_tables(class): version a feature class's tables as part of object class 'feature'.
-- Its tables are tgsis.class_tables's rows; the feature table comes before
-- the property tables that refer to its features (iudorder 3, then 4). A
-- property table stored in chunks (tgsis.store_class_in_chunks) is refused
-- by name (TG300): versioning property chunks is not built yet.
CREATE FUNCTION tgsis.version_class_tables(p_class text)
RETURNS void
LANGUAGE plpgsql
VOLATILE
AS $$
DECLARE
    v_class tgsis.catalog := tgsis.catalog_row(p_class);
    v_table record;
BEGIN
    EXECUTE format('DROP VIEW IF EXISTS %I.%I', v_class.schemaname, v_class.viewname);  -- re-created over the versioned views
    FOR v_table IN SELECT t.schemaname, t.tablename, t.kind FROM tgsis.class_tables t
                    WHERE t.classname = p_class ORDER BY t.position LOOP
        CONTINUE WHEN EXISTS (SELECT FROM tgsis.versioned_tables
                               WHERE schemaname = v_table.schemaname AND tablename = v_table.tablename);
        -- a property table stored in chunks (tgsis.store_class_in_chunks) has no rows to version: refused by name
        IF to_regclass(format('%I.%I', v_table.schemaname, v_table.tablename || '_shape')) IS NOT NULL
           AND to_regclass(format('%I.%I', v_table.schemaname, v_table.tablename || '_chunk')) IS NOT NULL
           AND (SELECT c.relkind FROM pg_class c WHERE c.oid = to_regclass(format('%I.%I', v_table.schemaname, v_table.tablename))) = 'v' THEN
            RAISE EXCEPTION 'feature class % cannot be versioned while its properties are stored in chunks', p_class
                USING ERRCODE = 'TG300',
                      DETAIL = format('%I.%I is a face over %I.%I; versioning property chunks is not built. '
                                      'SELECT tgsis.store_class_in_rows(%L) stores them as rows again. Nothing was changed.',
                                      v_table.schemaname, v_table.tablename, v_table.schemaname, v_table.tablename || '_chunk', p_class);
        END IF;
        PERFORM tgsis.enable_versioning_rel(format('%I.%I', v_table.schemaname, v_table.tablename)::regclass,
                                            '_geoid', 'feature', CASE v_table.kind WHEN 'feature' THEN 3 ELSE 4 END,
                                            v_table.schemaname || '.' || v_table.tablename);
    END LOOP;
END
$$;

COMMENT ON FUNCTION tgsis.version_class_tables(text) IS
    'version the tables of a feature class (tgsis.class_tables: feature, cell-property of both alignments, per-instant property) in object class ''feature'', keyed by _geoid; drops <class>_v for the caller to re-create';
