-- tgsis.drop_feature_class(name, force): remove a feature class; with force also its features and their geometries.
-- Table definitions are not versioned: a class is dropped in every version,
-- so its features' rows go from the storage of every version too.
-- A collection's owned members go with it, their cell properties with the table.
-- It runs as tgsis's owner (SECURITY DEFINER), who owns the class's tables
-- (see register_feature_class), for members of tgsis_admin.
CREATE FUNCTION tgsis.drop_feature_class(p_name text, p_force boolean DEFAULT false)
RETURNS bigint
LANGUAGE plpgsql
VOLATILE
SECURITY DEFINER
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_class tgsis.catalog;
    v_count bigint;
    v_ids   bigint[];
    v_table text;
    v_all   bigint[];
BEGIN
    IF NOT pg_has_role(tgsis.calling_role(), 'tgsis_admin', 'MEMBER') THEN
        RAISE EXCEPTION 'role % may not drop feature classes', tgsis.calling_role()
            USING ERRCODE = 'TG002', DETAIL = 'Dropping feature classes is for members of tgsis_admin.',
                  HINT = format('a DBA may run: GRANT tgsis_admin TO %I', tgsis.calling_role());
    END IF;
    SELECT * INTO v_class FROM tgsis.catalog WHERE classname = p_name FOR UPDATE;
    IF NOT FOUND THEN
        RAISE EXCEPTION 'feature class % does not exist', coalesce(quote_literal(p_name), 'NULL')
            USING ERRCODE = 'TG200', HINT = 'SELECT classname FROM tgsis.catalog lists the classes';
    END IF;
    -- its PostGIS view, if tgsis.create_postgis_view made one (sql/postgis/create_postgis_view.sql)
    IF (SELECT obj_description(c.oid, 'pg_class') LIKE 'tgsis PostGIS view %' AND c.relkind = 'v'
               AND c.relowner = (SELECT relowner FROM pg_class WHERE oid = 'tgsis.catalog'::regclass)
          FROM pg_class c WHERE c.oid = to_regclass(format('%I.%I', v_class.schemaname, v_class.classname || '_postgis'))) THEN
        EXECUTE format('DROP VIEW %I.%I', v_class.schemaname, v_class.classname || '_postgis');
    END IF;
    EXECUTE format('SELECT count(DISTINCT _geoid), array_agg(DISTINCT _geoid) FROM %s',
                   tgsis.storage_table(v_class.schemaname, v_class.featuretable))
       INTO v_count, v_ids;
    IF v_count > 0 AND NOT p_force THEN
        RAISE EXCEPTION 'feature class % still has % feature(s)', p_name, v_count
            USING ERRCODE = 'TG202',
                  DETAIL = 'Features stored in any version count.',
                  HINT = 'delete them first, or drop with force => true to delete them with their geometries';
    END IF;
    IF v_count > 0 THEN
        -- the features' geometries and the collection members they own (not geometries a collection only lists)
        EXECUTE format('SELECT $1 || coalesce(array_agg(DISTINCT geoid), ''{}'') FROM %s WHERE collection = ANY ($1)',
                       tgsis.storage_table('tgsis', 'geometry'))
           INTO v_all USING v_ids;
        PERFORM tgsis.delete_stored_geometries(v_all);
    END IF;
    EXECUTE format('DROP VIEW %I.%I', v_class.schemaname, v_class.viewname);
    FOR v_table IN SELECT t.tablename FROM tgsis.class_tables t WHERE t.classname = p_name ORDER BY t.position DESC LOOP
        IF tgsis.stored_in_chunks(v_class.schemaname, v_table) THEN
            -- stored in chunks (tgsis.store_class_in_chunks), versioned or not: the face, the decoded view, the
            -- chunks, the row definition, and a versioned table's registration; first the session's work tables of
            -- writes through the face in this transaction (tgsis.chunk_face_work: typed by the face's row type,
            -- dropped at the commit, they would keep the face from being dropped: 2BP01)
            EXECUTE (SELECT format('DROP TABLE IF EXISTS %s', string_agg(tgsis.chunk_face_work(format('%I.%I', v_class.schemaname, v_table), k), ', '))
                       FROM unnest(ARRAY['rows', 'dels', 'queue', 'now']) AS k);
            EXECUTE format('DROP VIEW %I.%I', v_class.schemaname, v_table);
            EXECUTE format('DROP FUNCTION IF EXISTS %I.%I()', v_class.schemaname, v_table || '_face_row');
            EXECUTE format('DROP VIEW %I.%I', v_class.schemaname, v_table || '_chunk_rows');
            EXECUTE format('DROP TABLE %I.%I', v_class.schemaname, v_table || '_chunk');
            EXECUTE format('DROP TABLE %I.%I', v_class.schemaname, v_table || '_shape');
            DELETE FROM tgsis.versioned_tables WHERE schemaname = v_class.schemaname AND tablename = v_table;
            DELETE FROM tgsis.revision_objects WHERE schemaname = v_class.schemaname AND tablename = v_table;
            DELETE FROM tgsis.versioning_dropped WHERE schemaname = v_class.schemaname AND tablename = v_table;
        ELSIF EXISTS (SELECT FROM tgsis.versioned_tables WHERE schemaname = v_class.schemaname AND tablename = v_table) THEN
            EXECUTE format('DROP VIEW %I.%I', v_class.schemaname, v_table);
            EXECUTE format('DROP FUNCTION %I.%I()', v_class.schemaname, v_table || '_ver_write');
            EXECUTE format('DROP TABLE %I.%I', v_class.schemaname, v_table || '_ver_queue');
            EXECUTE format('DROP FUNCTION IF EXISTS %I.%I(boolean, text, text[], integer[], integer[], integer, bigint[])',
                           v_class.schemaname, v_table || '_ver_run');
            EXECUTE format('DROP TABLE %I.%I', v_class.schemaname, v_table || '_ver');
            DELETE FROM tgsis.versioned_tables WHERE schemaname = v_class.schemaname AND tablename = v_table;
            DELETE FROM tgsis.revision_objects WHERE schemaname = v_class.schemaname AND tablename = v_table;
            DELETE FROM tgsis.versioning_dropped WHERE schemaname = v_class.schemaname AND tablename = v_table;
        ELSE
            EXECUTE format('DROP TABLE %I.%I', v_class.schemaname, v_table);
        END IF;
    END LOOP;
    DELETE FROM tgsis.catalog WHERE classname = p_name;
    RETURN v_count;
END
$$;

COMMENT ON FUNCTION tgsis.drop_feature_class(text, boolean) IS
    'drop a feature class and its tables (tgsis_admin members) (in every version); refuses (TG202) while features exist unless force, which deletes them and their geometries (with the members collections own); returns the number of features deleted';
