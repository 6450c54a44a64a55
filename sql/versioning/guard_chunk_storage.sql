-- tgsis.guard_chunk_storage(table): make tgsis.<table>_chunk of a versioned model table stored in chunks guarded as <table>_ver storage is.
-- tgsis.enable_versioning_rel guards a table's <table>_ver: other roles keep
-- SELECT and INSERT on it (the client's COPY of new objects), lose UPDATE,
-- DELETE, TRUNCATE, REFERENCES and TRIGGER (changes and closes go through the
-- view and tgsis's functions), a direct writer needs the write right on its
-- session's version (tgsis.storage_write_check) and may only add open
-- versions of its working revision, of objects no other version locked
-- (tgsis.storage_rows_check), and every direct insert notes its objects in
-- tgsis.revision_objects (tgsis.record_inserted_objects). A chunk table is
-- versioned storage too (its chunk versions carry revision and lastrevs): a
-- role that could still UPDATE it, or INSERT chunk versions of another
-- version's revision, would rewrite what other versions see. The same rights
-- and triggers, with the table's name given to the triggers (the storage is
-- not <table>_ver). The WHEN of the triggers spares the storage's and tgsis's
-- owners (the face's writer, tgsis.write_chunk_rows, merges). Called by
-- tgsis.enable_feature_versioning for a table stored in chunks, and by the
-- storage switch of a versioned table; tgsis.disable_versioning_rel undoes it.
-- A feature class's property table stored in chunks is named as the chunk
-- layer names it, schema-qualified ('public.rock_cellpros': its chunk table
-- is <schema>.<table>_chunk; tgsis.version_class_tables, the switch of a
-- versioned class, tgsis.store_class_in_chunks); a model table bare ('vrtx').
-- Internal: tgsis's owner, who owns the storage.
CREATE FUNCTION tgsis.guard_chunk_storage(p_table text)
RETURNS void
LANGUAGE plpgsql
VOLATILE
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_t       tgsis.versioned_tables;
    v_chunk   regclass;
    v_owner   text;
    v_skip    text;
    v_grantee oid;
    v_name    text[] := CASE WHEN strpos(p_table, '.') > 0 THEN parse_ident(p_table) ELSE ARRAY['tgsis', p_table] END;
BEGIN
    SELECT * INTO v_t FROM tgsis.versioned_tables t WHERE t.schemaname = v_name[1] AND t.tablename = v_name[2];
    IF NOT FOUND OR cardinality(v_name) <> 2 OR NOT tgsis.stored_in_chunks(v_name[1], v_name[2]) THEN
        RAISE EXCEPTION '% is not a versioned table stored in chunks', p_table
            USING ERRCODE = 'TG200';
    END IF;
    v_chunk := tgsis.storage_table(v_t.schemaname, v_t.tablename)::regclass;
    v_owner := (SELECT pg_get_userbyid(c.relowner) FROM pg_class c WHERE c.oid = v_chunk);
    FOR v_grantee IN
        SELECT DISTINCT a.grantee FROM pg_class c, aclexplode(c.relacl) AS a
         WHERE c.oid = v_chunk AND a.grantee <> c.relowner
           AND a.privilege_type IN ('UPDATE', 'DELETE', 'TRUNCATE', 'REFERENCES', 'TRIGGER')
    LOOP
        EXECUTE format('REVOKE UPDATE, DELETE, TRUNCATE, REFERENCES, TRIGGER ON %s FROM %s', v_chunk,
                       CASE WHEN v_grantee = 0 THEN 'PUBLIC' ELSE quote_ident(pg_get_userbyid(v_grantee)) END);
    END LOOP;
    -- (by role name, not oid: a dump restored into another cluster keeps the names)
    v_skip := format('NOT pg_catalog.pg_has_role(current_user, %L::name, ''USAGE'') '
                     'AND NOT pg_catalog.pg_has_role(current_user, %L::name, ''USAGE'')',
                     v_owner, (SELECT pg_get_userbyid(n.nspowner) FROM pg_namespace n WHERE n.nspname = 'tgsis'));
    EXECUTE format('DROP TRIGGER IF EXISTS tgsis_storage_write ON %s', v_chunk);
    EXECUTE format('DROP TRIGGER IF EXISTS tgsis_storage_rows ON %s', v_chunk);
    EXECUTE format('DROP TRIGGER IF EXISTS tgsis_storage_changes ON %s', v_chunk);
    EXECUTE format('CREATE TRIGGER tgsis_storage_write BEFORE INSERT OR UPDATE OR DELETE OR TRUNCATE ON %s '
                   'FOR EACH STATEMENT WHEN (%s) EXECUTE FUNCTION tgsis.storage_write_check()', v_chunk, v_skip);
    EXECUTE format('CREATE TRIGGER tgsis_storage_rows AFTER INSERT ON %s REFERENCING NEW TABLE AS tgsis_new_rows '
                   'FOR EACH STATEMENT WHEN (%s) EXECUTE FUNCTION tgsis.storage_rows_check(%L, %L, %L)',
                   v_chunk, v_skip, v_t.objectclass, v_t.objectkeyfield, v_t.tablename);
    EXECUTE format('CREATE TRIGGER tgsis_storage_changes AFTER INSERT ON %s REFERENCING NEW TABLE AS tgsis_new_rows '
                   'FOR EACH STATEMENT WHEN (pg_catalog.pg_trigger_depth() = 0 OR CURRENT_USER <> %L::name) '
                   'EXECUTE FUNCTION tgsis.record_inserted_objects(%L, %L)',
                   v_chunk, v_owner, v_t.objectkeyfield, v_t.tablename);
END
$$;

REVOKE ALL ON FUNCTION tgsis.guard_chunk_storage(text) FROM PUBLIC;

COMMENT ON FUNCTION tgsis.guard_chunk_storage(text) IS
    'guard the chunk table (tgsis.<table>_chunk, or <schema>.<table>_chunk of a class''s property table named schema-qualified) of a versioned table stored in chunks as tgsis.enable_versioning_rel guards <table>_ver: other roles lose UPDATE, DELETE, TRUNCATE, REFERENCES, TRIGGER on it; direct writers need the write right and may add only open chunk versions of their working revision (tgsis.storage_write_check, storage_rows_check), noted in tgsis.revision_objects (record_inserted_objects)';
