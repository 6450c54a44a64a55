-- tgsis.protect_model_tables(model): the row-level security of a data model's storage tables, keyed by the classes' rights.
-- docs/security.md advises granting per class; the features of every class
-- keep their geometry in the tables of their model, which every class shares
-- (tgsis.geometry, tgsis.vrtx, tgsis.trgl, the tables of models 2 to 5). So
-- each such table (the ones with a geoid column, tgsis.model_tables) gets
-- policies that keep from a role the rows of the features of the classes on
-- whose table it lacks the right (tgsis.class_denied_geoids): SELECT to read
-- them, UPDATE to insert or change them, UPDATE or DELETE to delete them.
-- The policies sit on the storage: the table while it is plain, <table>_ver
-- once versioned (a rename keeps them), <table>_chunk once stored in chunks
-- (tgsis.store_in_chunks copies them there: the face is a view). They guard the roles' own statements
-- on the storage; the versioned views read it as their owner, whom they
-- spare, and filter by the same set themselves as security barriers
-- (tgsis.create_versioned_view).
-- Owners (tgsis's owner, whose definer code checks rights itself with
-- tgsis.check_class_write) and superusers are not subject to them. Idempotent:
-- run again after storage is swapped (tgsis.partition_model_storage) and by
-- the upgrade.
CREATE FUNCTION tgsis.protect_model_tables(p_model smallint)
RETURNS void
LANGUAGE plpgsql
VOLATILE
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_t     record;
    v_rel   regclass;
    v_check text;
    v_owner text;
BEGIN
    FOR v_t IN SELECT t.tablename, t.geoidcolumn FROM tgsis.model_tables t
                WHERE t.model = p_model AND t.geoidcolumn IS NOT NULL ORDER BY t.tablename LOOP
        v_rel := coalesce(to_regclass(format('tgsis.%I', v_t.tablename || '_ver')),
                          to_regclass(format('tgsis.%I', v_t.tablename || CASE WHEN tgsis.stored_in_chunks(v_t.tablename)
                                                                                 THEN '_chunk' ELSE '' END)));
        CONTINUE WHEN v_rel IS NULL;
        -- a row a collection owns (tgsis.geometry.collection) is that collection's class's: it may be
        -- made or moved there only by a role that may change that class
        v_owner := CASE WHEN EXISTS (SELECT FROM pg_catalog.pg_attribute a WHERE a.attrelid = v_rel AND a.attname = 'collection'
                                                                           AND NOT a.attisdropped)
                        THEN format(' AND (collection IS NULL OR %s)', tgsis.class_rights_filter('collection', 'UPDATE')) ELSE '' END;
        EXECUTE format('ALTER TABLE %s ENABLE ROW LEVEL SECURITY', v_rel);
        EXECUTE format('DROP POLICY IF EXISTS tgsis_class_read ON %s', v_rel);
        EXECUTE format('DROP POLICY IF EXISTS tgsis_class_insert ON %s', v_rel);
        EXECUTE format('DROP POLICY IF EXISTS tgsis_class_update ON %s', v_rel);
        EXECUTE format('DROP POLICY IF EXISTS tgsis_class_delete ON %s', v_rel);
        EXECUTE format('CREATE POLICY tgsis_class_read ON %s FOR SELECT USING (%s)', v_rel, tgsis.class_rights_filter(v_t.geoidcolumn, 'SELECT'));
        v_check := tgsis.class_rights_filter(v_t.geoidcolumn, 'UPDATE');
        EXECUTE format('CREATE POLICY tgsis_class_insert ON %s FOR INSERT WITH CHECK (%s%s)', v_rel, v_check, v_owner);
        EXECUTE format('CREATE POLICY tgsis_class_update ON %s FOR UPDATE USING (%s) WITH CHECK (%s%s)', v_rel,
                       v_check, v_check, v_owner);
        EXECUTE format('CREATE POLICY tgsis_class_delete ON %s FOR DELETE USING (%s)', v_rel,
                       tgsis.class_rights_filter(v_t.geoidcolumn, 'UPDATE, DELETE'));
        EXECUTE format('COMMENT ON POLICY tgsis_class_read ON %s IS %L', v_rel,
                       'per-class rights: rows of features of classes the role may not SELECT are not seen (tgsis.class_denied_geoids)');
        EXECUTE format('COMMENT ON POLICY tgsis_class_insert ON %s IS %L', v_rel,
                       'per-class rights: rows for features of classes the role may not UPDATE are refused');
        EXECUTE format('COMMENT ON POLICY tgsis_class_update ON %s IS %L', v_rel,
                       'per-class rights: rows of features of classes the role may not UPDATE are not changed');
        EXECUTE format('COMMENT ON POLICY tgsis_class_delete ON %s IS %L', v_rel,
                       'per-class rights: rows of features of classes the role may neither UPDATE nor DELETE are not deleted');
    END LOOP;
END
$$;

REVOKE ALL ON FUNCTION tgsis.protect_model_tables(smallint) FROM PUBLIC;

COMMENT ON FUNCTION tgsis.protect_model_tables(smallint) IS
    'enable row-level security on the storage tables of a data model that hold rows per geoid (<table>_ver when versioned, <table>_chunk when stored in chunks), with policies keyed by the rights on the feature classes (tgsis.class_denied_geoids); idempotent; called by tgsis.create_storage, tgsis.partition_model_storage and the upgrade';
