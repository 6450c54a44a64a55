-- tgsis.version_class_tables(class): version a feature class's tables as part of object class 'feature'.
-- Its tables are tgsis.class_tables's rows; the feature table comes before
-- the property tables that refer to its features (iudorder 3, then 4). A
-- property table stored in chunks (tgsis.store_class_in_chunks) is versioned
-- in place: registered, its face given the write right's check and its
-- chunk table guarded (tgsis.guard_chunk_storage); its chunk versions, all of
-- revision 0, are what every version sees.
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
        -- a property table stored in chunks (tgsis.store_class_in_chunks): its chunk versions carry revision and
        -- lastrevs already (all of revision 0) and the face decides visibility at each read, so versioning is the
        -- registration, the write right's statement check of a versioned view and the guard of its storage, as
        -- tgsis.enable_feature_versioning does for a model table stored in chunks
        IF tgsis.stored_in_chunks(v_table.schemaname, v_table.tablename) THEN
            INSERT INTO tgsis.versioned_tables (schemaname, tablename, shortname, objectkeyfield, objectclass, iudorder,
                                                keycolumns, pkeyname, tablecomment, enabled_by)
            SELECT v_table.schemaname, v_table.tablename, v_table.schemaname || '.' || v_table.tablename, '_geoid', 'feature',
                   CASE v_table.kind WHEN 'feature' THEN 3 ELSE 4 END,
                   array_agg(a.attname::text ORDER BY k.ord), v_table.tablename || '_pkey',
                   -- (the table's own comment, which the face's starts with: as when switched while versioned)
                   split_part(obj_description(format('%I.%I', v_table.schemaname, v_table.tablename)::regclass, 'pg_class'),
                              ', stored in chunks (', 1),
                   tgsis.calling_role()
              FROM pg_constraint con
             CROSS JOIN LATERAL unnest(con.conkey) WITH ORDINALITY AS k(attnum, ord)
              JOIN pg_attribute a ON a.attrelid = con.conrelid AND a.attnum = k.attnum
             WHERE con.conrelid = format('%I.%I', v_table.schemaname, v_table.tablename || '_shape')::regclass
               AND con.contype = 'p';
            EXECUTE format('CREATE TRIGGER tgsis_versioning_rights BEFORE INSERT OR UPDATE OR DELETE ON %I.%I '
                           'FOR EACH STATEMENT EXECUTE FUNCTION tgsis.view_write_check()', v_table.schemaname, v_table.tablename);
            PERFORM tgsis.guard_chunk_storage(format('%I.%I', v_table.schemaname, v_table.tablename));
            EXECUTE format('ANALYZE %I.%I', v_table.schemaname, v_table.tablename || '_chunk');
            CONTINUE;
        END IF;
        PERFORM tgsis.enable_versioning_rel(format('%I.%I', v_table.schemaname, v_table.tablename)::regclass,
                                            '_geoid', 'feature', CASE v_table.kind WHEN 'feature' THEN 3 ELSE 4 END,
                                            v_table.schemaname || '.' || v_table.tablename);
    END LOOP;
END
$$;

COMMENT ON FUNCTION tgsis.version_class_tables(text) IS
    'version the tables of a feature class (tgsis.class_tables: feature, cell-property of both alignments, per-instant property) in object class ''feature'', keyed by _geoid; drops <class>_v for the caller to re-create';
