-- tgsis.enable_feature_versioning(): version model 1 and every feature class as one object class, 'feature', keyed by geoid.
-- iudorder: the storage tables' own (tgsis.model_tables: geometry 0, vertices,
-- instants and periods 1, the rest 2), feature tables 3, property tables 4.
-- Classes registered later are versioned as they are created. Classes
-- registered without versioning (tgsis.catalog.versioned) keep plain tables;
-- the rows of their features in the storage tables become rows of no
-- version (revision 0, as every existing row, never closed: the writers
-- read tgsis.unversioned_features).
CREATE FUNCTION tgsis.enable_feature_versioning()
RETURNS integer
LANGUAGE plpgsql
VOLATILE
SECURITY DEFINER
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_table text;
    v_order integer;
    v_objectclass text;
    v_key   text;
    v_class text;
    v_count integer;
    v_con   record;
BEGIN
    PERFORM tgsis.require_storage();  -- a bare CREATE EXTENSION: say what to run (geometry/require_storage.sql)
    SELECT count(*) INTO v_count FROM tgsis.versioned_tables
     WHERE objectclass = 'feature' OR (schemaname = 'tgsis' AND tablename IN (SELECT tablename FROM tgsis.model_tables));
    FOR v_class IN SELECT classname FROM tgsis.catalog WHERE versioned ORDER BY classname LOOP  -- not classes registered without
        PERFORM tgsis.version_class_tables(v_class);
    END LOOP;
    -- the views of classes without versioning read tgsis.geometry: made again over its view below
    FOR v_class IN SELECT classname FROM tgsis.catalog WHERE NOT versioned ORDER BY classname LOOP
        EXECUTE format('DROP VIEW IF EXISTS %I.%I', (SELECT schemaname FROM tgsis.catalog WHERE classname = v_class),
                       (SELECT viewname FROM tgsis.catalog WHERE classname = v_class));
    END LOOP;
    -- the feature tables of classes without versioning stay plain: their key to tgsis.geometry cannot
    -- hold once that is a view; recorded as versioning records what it drops (disable_feature_versioning
    -- restores it)
    FOR v_con IN
        SELECT con.oid, con.conrelid, con.conname
          FROM tgsis.catalog c JOIN pg_constraint con
            ON con.conrelid = to_regclass(format('%I.%I', c.schemaname, c.featuretable))
         WHERE NOT c.versioned AND con.contype = 'f' AND con.confrelid = to_regclass('tgsis.geometry')
           AND NOT EXISTS (SELECT FROM tgsis.versioned_tables WHERE schemaname = 'tgsis' AND tablename = 'geometry')
         ORDER BY c.classname
    LOOP
        PERFORM tgsis.record_dropped('tgsis.geometry'::regclass, v_con.oid);
        EXECUTE format('ALTER TABLE %s DROP CONSTRAINT %I', v_con.conrelid::regclass, v_con.conname);
    END LOOP;
    -- the storage of every data model (tgsis.model_tables), referenced rows first
    FOR v_table, v_order, v_objectclass, v_key IN
        SELECT tablename, iudorder, objectclass, keycolumn FROM tgsis.model_tables ORDER BY model, iudorder, tablename LOOP
        IF EXISTS (SELECT FROM tgsis.versioned_tables WHERE schemaname = 'tgsis' AND tablename = v_table) THEN
            CONTINUE;
        ELSIF tgsis.stored_in_chunks(v_table) THEN
            -- stored in chunks (tgsis.store_in_chunks): the chunk versions carry revision and lastrevs
            -- already (all of revision 0) and the face decides visibility at each read, so versioning is
            -- the registration and the write right's statement check of a versioned view
            INSERT INTO tgsis.versioned_tables (schemaname, tablename, shortname, objectkeyfield, objectclass, iudorder,
                                                keycolumns, pkeyname, tablecomment, enabled_by)
            SELECT 'tgsis', v_table, v_table, v_key, v_objectclass, v_order,
                   array_agg(a.attname::text ORDER BY k.ord), v_table || '_pkey',
                   obj_description(format('tgsis.%I', v_table)::regclass, 'pg_class'), tgsis.calling_role()
              FROM pg_constraint con
             CROSS JOIN LATERAL unnest(con.conkey) WITH ORDINALITY AS k(attnum, ord)
              JOIN pg_attribute a ON a.attrelid = con.conrelid AND a.attnum = k.attnum
             WHERE con.conrelid = format('tgsis.%I', v_table || '_shape')::regclass AND con.contype = 'p';
            EXECUTE format('CREATE TRIGGER tgsis_versioning_rights BEFORE INSERT OR UPDATE OR DELETE ON tgsis.%I '
                           'FOR EACH STATEMENT EXECUTE FUNCTION tgsis.view_write_check()', v_table);
            PERFORM tgsis.guard_chunk_storage(v_table);  -- its rights and triggers as versioned storage
            -- statistics, as tgsis.enable_versioning_rel gives <table>_ver: the reads of versions are planned from them
            EXECUTE format('ANALYZE tgsis.%I', v_table || '_chunk');
        ELSE
            PERFORM tgsis.enable_versioning_rel(format('tgsis.%I', v_table)::regclass, v_key, v_objectclass, v_order);
        END IF;
    END LOOP;
    FOR v_class IN SELECT classname FROM tgsis.catalog ORDER BY classname LOOP
        PERFORM tgsis.create_class_view(v_class);
    END LOOP;
    RETURN (SELECT count(*) FROM tgsis.versioned_tables
             WHERE objectclass = 'feature' OR (schemaname = 'tgsis' AND tablename IN (SELECT tablename FROM tgsis.model_tables)))
           - v_count;
END
$$;

REVOKE ALL ON FUNCTION tgsis.enable_feature_versioning() FROM PUBLIC;

COMMENT ON FUNCTION tgsis.enable_feature_versioning() IS
    'version the storage tables of every data model (tgsis.model_tables: geometry, vrtx, simplices, the model-2 and model-3 tables, ...) and every feature class''s tables (but those of classes registered without versioning) as object class ''feature'' (key geoid/_geoid); returns the number of tables newly versioned';
