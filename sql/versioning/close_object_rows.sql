-- tgsis.close_object_rows(schema, table, keyfield, keys, idfield, ids): the versioned half of tgsis.delete_object_rows.
-- SECURITY DEFINER: roles other than storage's owner may not update or
-- delete rows of <table>_ver (they could rewrite other versions), so the
-- set-based delete of the client runs here, for the calling role, after the
-- checks a write through the view makes: the table is one tgsis versions
-- (tgsis.versioned_tables, which only tgsis writes), the role may DELETE
-- from its view (and, on the model tables every class shares, change the
-- features' classes: tgsis.check_class_write), holds the write right on its session's version
-- (tgsis.write_revision) and no other version locked the objects. The
-- objects' write locks are taken exclusively first: no write through the
-- view is in flight on them (it would re-create a closed row), later ones
-- find them changed. Rows written in the working revision go, older visible
-- rows get the working revision appended to lastrevs (the objects noted in
-- tgsis.revision_objects); rows of features of
-- classes without versioning (tgsis.unversioned_features, revision 0) go,
-- in DEFAULT's working revision only. Returns rows affected.
CREATE FUNCTION tgsis.close_object_rows(p_schema text, p_table text, p_keyfield text, p_keys bigint[],
                                        p_idfield text DEFAULT NULL, p_ids bigint[] DEFAULT NULL)
RETURNS bigint
LANGUAGE plpgsql
VOLATILE
SECURITY DEFINER
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_t       tgsis.versioned_tables;
    v_write   record;
    v_deleted bigint;
    v_closed  bigint;
    v_where   text;
    v_none    bigint[];
    v_gone    bigint := 0;
    v_storage text := tgsis.storage_table(p_schema, p_table);  -- <table>_ver, or tgsis.<table>_chunk
BEGIN
    PERFORM tgsis.require_read_committed('a set-based delete of versioned objects');
    -- a chunk holds 1024 ids of an object: some of its rows go by rewriting it, which is the chunk writer's
    -- work (tgsis.write_chunk_rows, a later layer); here whole objects only, never a chunk dropped for a row
    IF p_idfield IS NOT NULL AND tgsis.stored_in_chunks(p_schema, p_table) THEN
        RAISE EXCEPTION 'tgsis.% is stored in chunks: some rows of an object are deleted by rewriting its chunks', quote_ident(p_table)
            USING ERRCODE = 'TG100',
                  DETAIL = format('Rows %s = any of %s of objects %s were to be deleted; tgsis.close_object_rows deletes whole objects '
                                  'of a table stored in chunks, tgsis.write_chunk_rows writes rows of them.',
                                  quote_ident(p_idfield), coalesce(left(p_ids::text, 80), 'NULL'), left(p_keys::text, 80));
    END IF;
    SELECT * INTO v_t FROM tgsis.versioned_tables WHERE schemaname = p_schema AND tablename = p_table;
    IF NOT FOUND THEN
        RAISE EXCEPTION 'table %.% is not versioned', quote_ident(p_schema), quote_ident(p_table)
            USING ERRCODE = 'TG200', HINT = 'SELECT * FROM tgsis.versioned_tables lists the versioned tables';
    END IF;
    IF p_keyfield IS DISTINCT FROM v_t.objectkeyfield THEN
        RAISE EXCEPTION 'the object key of %.% is %, not %', quote_ident(p_schema), quote_ident(p_table),
                quote_ident(v_t.objectkeyfield), coalesce(quote_ident(p_keyfield), 'NULL')
            USING ERRCODE = 'TG100';
    END IF;
    IF p_idfield IS NOT NULL AND NOT EXISTS (
            SELECT FROM pg_attribute WHERE attrelid = format('%I.%I', p_schema, p_table)::regclass
                                        AND attname = p_idfield AND attnum > 0 AND NOT attisdropped) THEN
        RAISE EXCEPTION 'table %.% has no column %', quote_ident(p_schema), quote_ident(p_table), quote_ident(p_idfield)
            USING ERRCODE = 'TG100';
    END IF;
    -- (42501 as PostgreSQL refuses the DELETE of the view itself, and as the merges of every data model refuse
    -- a write of a property view the role may not make: tgsis.check_merge_table_write)
    IF NOT has_table_privilege(tgsis.calling_role(), format('%I.%I', p_schema, p_table)::regclass, 'DELETE') THEN
        RAISE EXCEPTION 'role % may not delete from %.%', quote_ident(tgsis.calling_role()), quote_ident(p_schema),
                quote_ident(p_table)
            USING ERRCODE = 'insufficient_privilege', HINT = 'its owner can GRANT DELETE on it';
    END IF;
    -- a model table every feature class shares: the right on each feature's class (42501; a part of a
    -- feature's rows changes it: UPDATE; all its rows go with the feature: UPDATE or DELETE)
    IF p_schema = 'tgsis' AND EXISTS (SELECT FROM tgsis.model_tables t WHERE t.tablename = p_table AND t.geoidcolumn = p_keyfield) THEN
        PERFORM tgsis.check_class_write(p_keys, CASE WHEN p_idfield IS NULL THEN 'UPDATE, DELETE' ELSE 'UPDATE' END);
    END IF;
    SELECT * INTO v_write FROM tgsis.write_revision();
    PERFORM tgsis.check_objects_unlocked(v_t.objectclass, p_keys::text[]);
    PERFORM tgsis.object_write_lock(v_t.objectclass, p_keys::text[]);
    -- as the storage's owner (tgsis.storage_run): $1 keys, $3 the working set, $4 the working revision, $5 ids
    v_where := format('%I = ANY ($1::bigint[])', p_keyfield)
               || CASE WHEN p_idfield IS NOT NULL THEN format(' AND %I = ANY ($5)', p_idfield) ELSE '' END;
    -- features of classes without versioning: their rows (revision 0) go for good, in DEFAULT's working revision only
    IF v_t.objectclass = 'feature' THEN
        v_none := ARRAY(SELECT u.geoid FROM tgsis.unversioned_features u WHERE u.geoid = ANY (p_keys));
    END IF;
    IF cardinality(v_none) > 0 THEN
        PERFORM tgsis.unversioned_revision(v_none);  -- TG305
        SELECT r[1]::bigint INTO v_gone FROM tgsis.storage_run(v_t, true, format(
            'DELETE FROM %s WHERE %s AND revision = 0', v_storage, v_where),
            v_none::text[], NULL, v_write.revisions, v_write.revision, p_ids) AS r;
        p_keys := ARRAY(SELECT k FROM unnest(p_keys) AS k WHERE k <> ALL (v_none));
    END IF;
    SELECT r[1]::bigint INTO v_deleted FROM tgsis.storage_run(v_t, true, format(
        'DELETE FROM %s WHERE %s AND revision = $4', v_storage, v_where),
        p_keys::text[], NULL, v_write.revisions, v_write.revision, p_ids) AS r;
    SELECT r[1]::bigint INTO v_closed FROM tgsis.storage_run(v_t, true, format(
        'UPDATE %s v SET lastrevs = v.lastrevs || $4
          WHERE %s AND (v.revision = ANY ($3)) IS TRUE AND NOT (v.lastrevs && $3)', v_storage, v_where),
        p_keys::text[], NULL, v_write.revisions, v_write.revision, p_ids) AS r;
    IF v_closed > 0 THEN
        PERFORM tgsis.note_changed_objects(p_schema, p_table, v_write.revision, p_keys::text[]);  -- tgsis.revision_objects
    END IF;
    RETURN v_gone + v_deleted + v_closed;
END
$$;

COMMENT ON FUNCTION tgsis.close_object_rows(text, text, text, bigint[], text, bigint[]) IS
    'set-based delete of objects'' rows (some of them with idfield/ids) from a versioned table in the session''s version, for roles that may not write its storage: checks DELETE on the view, the write right, object locks; takes the objects'' write locks; returns rows affected';
