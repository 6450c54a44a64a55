-- tgsis.disable_versioning_rel(view, force): the work of tgsis.disable_versioning on a resolved view.
-- Refuses while versions other than DEFAULT have changes in it (they would be
-- lost) unless forced. A model table stored in chunks (tgsis.stored_in_chunks)
-- keeps its chunk table and face: the chunk versions DEFAULT does not see go,
-- the others become revision 0, open (unversioned chunk storage: every chunk
-- version is the one state), and the storage's triggers go with the face's
-- write-right check; the face shows every chunk version from then on.
CREATE FUNCTION tgsis.disable_versioning_rel(p_table regclass, p_force boolean DEFAULT false)
RETURNS bigint
LANGUAGE plpgsql
VOLATILE
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_t         tgsis.versioned_tables := tgsis.versioned_table(p_table);
    v_view      regclass;
    v_ver       text := v_t.tablename || '_ver';
    v_storage   text := tgsis.storage_table(v_t.schemaname, v_t.tablename);  -- <table>_ver, or tgsis.<table>_chunk
    v_default   integer[];
    v_dependent text;
    v_name      text;
    v_removed   bigint;
    v_acl       record;
BEGIN
    v_view := format('%I.%I', v_t.schemaname, v_t.tablename)::regclass;
    IF NOT pg_has_role(current_user, (SELECT relowner FROM pg_class WHERE oid = v_view), 'USAGE') THEN
        RAISE EXCEPTION 'only the owner of %.% may stop versioning it', v_t.schemaname, v_t.tablename USING ERRCODE = 'TG002';
    END IF;
    SELECT string_agg(DISTINCT r.ev_class::regclass::text, ', ') INTO v_dependent
      FROM pg_depend d JOIN pg_rewrite r ON d.classid = 'pg_rewrite'::regclass AND d.objid = r.oid
     WHERE d.refclassid = 'pg_class'::regclass AND d.refobjid = v_view AND r.ev_class <> v_view;
    IF v_dependent IS NOT NULL THEN
        RAISE EXCEPTION 'views depend on %.%: %', v_t.schemaname, v_t.tablename, v_dependent
            USING ERRCODE = 'TG202', HINT = 'drop them first and create them again afterwards';
    END IF;
    SELECT workingset INTO v_default FROM tgsis.versions WHERE versionid = 0;
    IF NOT coalesce(p_force, false) THEN
        EXECUTE format('SELECT string_agg(DISTINCT x.name, '', '') FROM %s v, tgsis.revisions r, tgsis.versions x
                         WHERE x.versionid = r.versionid AND r.versionid <> 0
                           AND (r.revision = v.revision OR r.revision = ANY (v.lastrevs))', v_storage)
           INTO v_dependent;
        IF v_dependent IS NOT NULL THEN
            RAISE EXCEPTION 'versions other than DEFAULT changed %.%: %', v_t.schemaname, v_t.tablename, v_dependent
                USING ERRCODE = 'TG202',
                      DETAIL = 'Only the rows DEFAULT sees now are kept; those changes would be lost.',
                      HINT = 'merge or delete those versions first, or pass p_force => true';
        END IF;
    END IF;

    IF tgsis.stored_in_chunks(v_t.schemaname, v_t.tablename) THEN
        -- the rights the chunk table did not keep while versioned come back from the face (tgsis.enable_feature_versioning);
        -- a class's property chunks are written through the face alone, versioned or not (SELECT only: tgsis.create_chunk_table)
        FOR v_acl IN
            SELECT a.privilege_type, a.grantee FROM pg_class c, aclexplode(c.relacl) AS a
             WHERE c.oid = v_view AND a.grantee <> c.relowner AND v_t.schemaname = 'tgsis'
               AND a.privilege_type IN ('UPDATE', 'DELETE', 'TRUNCATE', 'REFERENCES', 'TRIGGER')
        LOOP
            EXECUTE format('GRANT %s ON %s TO %s', v_acl.privilege_type, v_storage,
                           CASE WHEN v_acl.grantee = 0 THEN 'PUBLIC' ELSE quote_ident(pg_get_userbyid(v_acl.grantee)) END);
        END LOOP;
        EXECUTE format('DROP TRIGGER IF EXISTS tgsis_versioning_rights ON %I.%I', v_t.schemaname, v_t.tablename);
        EXECUTE format('DROP TRIGGER IF EXISTS tgsis_storage_write ON %s', v_storage);
        EXECUTE format('DROP TRIGGER IF EXISTS tgsis_storage_rows ON %s', v_storage);
        EXECUTE format('DROP TRIGGER IF EXISTS tgsis_storage_changes ON %s', v_storage);
        -- DEFAULT's chunk versions stay, as revision 0: at most one per chunk (every set sees one version of a chunk)
        EXECUTE format('DELETE FROM %s v WHERE NOT (v.revision = ANY ($1) AND NOT (v.lastrevs && $1))', v_storage)
          USING v_default;
        GET DIAGNOSTICS v_removed = ROW_COUNT;
        EXECUTE format('UPDATE %s v SET revision = 0, lastrevs = ''{}'' WHERE v.revision <> 0 OR v.revclosed', v_storage);
        PERFORM tgsis.unregister_versioned_table(v_t.schemaname, v_t.tablename);
        PERFORM tgsis.restore_dropped_constraints(v_t.schemaname, v_t.tablename);
        RETURN v_removed;
    END IF;

    -- the rights storage did not keep (updates and deletes went through the view) come back from the view
    FOR v_acl IN
        SELECT a.privilege_type, a.grantee FROM pg_class c, aclexplode(c.relacl) AS a
         WHERE c.oid = v_view AND a.grantee <> c.relowner
           AND a.privilege_type IN ('UPDATE', 'DELETE', 'TRUNCATE', 'REFERENCES', 'TRIGGER')
    LOOP
        EXECUTE format('GRANT %s ON %I.%I TO %s', v_acl.privilege_type, v_t.schemaname, v_ver,
                       CASE WHEN v_acl.grantee = 0 THEN 'PUBLIC' ELSE quote_ident(pg_get_userbyid(v_acl.grantee)) END);
    END LOOP;
    EXECUTE format('DROP VIEW %I.%I', v_t.schemaname, v_t.tablename);
    EXECUTE format('DROP FUNCTION %I.%I()', v_t.schemaname, v_t.tablename || '_ver_write');
    EXECUTE format('DROP TABLE %I.%I', v_t.schemaname, v_t.tablename || '_ver_queue');
    EXECUTE format('DROP FUNCTION IF EXISTS %I.%I(boolean, text, text[], integer[], integer[], integer, bigint[])',
                   v_t.schemaname, v_t.tablename || '_ver_run');
    EXECUTE format('DELETE FROM %I.%I v WHERE NOT (v.revision = ANY ($1) AND NOT (v.lastrevs && $1))', v_t.schemaname, v_ver)
      USING v_default;
    GET DIAGNOSTICS v_removed = ROW_COUNT;
    EXECUTE format('DROP TRIGGER tgsis_storage_write ON %I.%I', v_t.schemaname, v_ver);
    EXECUTE format('DROP TRIGGER tgsis_storage_rows ON %I.%I', v_t.schemaname, v_ver);
    EXECUTE format('DROP TRIGGER tgsis_storage_changes ON %I.%I', v_t.schemaname, v_ver);
    EXECUTE format('ALTER TABLE %I.%I DROP CONSTRAINT %I', v_t.schemaname, v_ver, v_ver || '_pkey');
    EXECUTE format('ALTER TABLE %I.%I DROP COLUMN revision, DROP COLUMN revclosed, DROP COLUMN lastrevs', v_t.schemaname, v_ver);
    -- the revision indexes went with the columns; the BRIN on a cell table's geoid and vertex columns goes too
    -- (tgsis.create_revision_indexes made it for the versioned storage)
    FOR v_name IN
        SELECT c.relname FROM pg_index i JOIN pg_class c ON c.oid = i.indexrelid JOIN pg_am a ON a.oid = c.relam
         WHERE i.indrelid = format('%I.%I', v_t.schemaname, v_ver)::regclass AND a.amname = 'brin'
           AND (SELECT t.attnum FROM pg_attribute t WHERE t.attrelid = i.indrelid AND t.attname = 'vrtxid1') = ANY (i.indkey::int2[])
    LOOP
        EXECUTE format('DROP INDEX %I.%I', v_t.schemaname, v_name);
    END LOOP;
    EXECUTE format('ALTER TABLE %I.%I RENAME TO %I', v_t.schemaname, v_ver, v_t.tablename);
    EXECUTE format('ALTER TABLE %I.%I ADD CONSTRAINT %I PRIMARY KEY (%s)', v_t.schemaname, v_t.tablename, v_t.pkeyname,
                   (SELECT string_agg(format('%I', k), ', ' ORDER BY o) FROM unnest(v_t.keycolumns) WITH ORDINALITY AS u(k, o)));
    FOREACH v_name IN ARRAY v_t.identity_always LOOP
        EXECUTE format('ALTER TABLE %I.%I ALTER COLUMN %I SET GENERATED ALWAYS', v_t.schemaname, v_t.tablename, v_name);
    END LOOP;
    EXECUTE format('COMMENT ON TABLE %I.%I IS %L', v_t.schemaname, v_t.tablename, v_t.tablecomment);
    PERFORM tgsis.unregister_versioned_table(v_t.schemaname, v_t.tablename);
    PERFORM tgsis.restore_dropped_constraints(v_t.schemaname, v_t.tablename);
    RETURN v_removed;
END
$$;

COMMENT ON FUNCTION tgsis.disable_versioning_rel(regclass, boolean) IS
    'the work of tgsis.disable_versioning on a resolved view: make a versioned table plain again with the rows DEFAULT sees (refused while other versions changed it, unless p_force); restores dropped constraints; returns the row versions removed';
