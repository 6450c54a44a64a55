-- tgsis.delete_version(name): remove a leaf version, its revisions and its row versions; returns the rows removed.
CREATE FUNCTION tgsis.delete_version(p_name text)
RETURNS bigint
LANGUAGE plpgsql
VOLATILE
SECURITY DEFINER
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_id       integer := tgsis.version_id(p_name);
    v_children text;
    v_revs     integer[];
    v_t        tgsis.versioned_tables;
    v_keys     text[];
    v_objects  text;
    v_count    bigint;
    v_removed  bigint := 0;
BEGIN
    IF v_id = 0 THEN
        RAISE EXCEPTION 'version DEFAULT cannot be deleted' USING ERRCODE = 'TG100', DETAIL = 'It is the root of the version tree.';
    END IF;
    PERFORM tgsis.require_version_privilege(v_id, 'delete', 'delete');
    PERFORM FROM tgsis.versions WHERE versionid = v_id FOR UPDATE;
    IF NOT FOUND THEN
        -- deleted (or merged away) by the transaction this one waited for:
        -- say so rather than report 0 rows removed
        RAISE EXCEPTION 'version % does not exist', quote_literal(p_name)
            USING ERRCODE = 'TG200', DETAIL = 'It was deleted while this delete_version waited for it.';
    END IF;
    SELECT string_agg(quote_literal(name), ', ' ORDER BY name) INTO v_children FROM tgsis.versions WHERE parentid = v_id;
    IF v_children IS NOT NULL THEN
        RAISE EXCEPTION 'version % has child versions: %', quote_literal(p_name), v_children
            USING ERRCODE = 'TG202', HINT = 'delete (or merge) the children first';
    END IF;
    SELECT array_agg(revision ORDER BY revision) INTO v_revs FROM tgsis.revisions WHERE versionid = v_id;
    FOR v_t IN SELECT * FROM tgsis.versioned_tables ORDER BY iudorder DESC, schemaname, tablename LOOP
        -- only the objects noted as changed in its revisions have rows to go or to reopen (tgsis.revision_objects)
        v_keys := ARRAY(SELECT DISTINCT o.objectkey FROM tgsis.revision_objects o
                         WHERE o.revision = ANY (v_revs) AND o.schemaname = v_t.schemaname AND o.tablename = v_t.tablename);
        CONTINUE WHEN cardinality(v_keys) = 0;
        v_objects := format('v.%I = ANY ($1::%s[])', v_t.objectkeyfield, tgsis.object_key_type(v_t));
        -- as the storage's owner (tgsis.storage_run)
        SELECT r[1]::bigint INTO v_count FROM tgsis.storage_run(v_t, true, format(
            'DELETE FROM %s v WHERE %s AND v.revision = ANY ($2)', tgsis.storage_table(v_t.schemaname, v_t.tablename), v_objects),
            v_keys, v_revs) AS r;
        v_removed := v_removed + v_count;
        -- rows of ancestors that the version closed become live again for nobody else: drop its revisions
        -- (rows that sibling versions see too: changed without waiting for one while holding others)
        PERFORM tgsis.update_shared_rows(v_t,
                                         'lastrevs = ARRAY(SELECT r FROM unnest(v.lastrevs) AS r WHERE r <> ALL ($2))',
                                         v_objects || ' AND v.lastrevs && $2', v_keys, v_revs, NULL, NULL);
    END LOOP;
    DELETE FROM tgsis.revision_objects WHERE revision = ANY (v_revs);
    DELETE FROM tgsis.versions WHERE versionid = v_id;  -- its revisions go with it
    IF tgsis.get_working_version() = p_name THEN
        PERFORM set_config('tgsis.version', '', false);
        PERFORM set_config('tgsis.revision', '', false);
    END IF;
    RETURN v_removed;
END
$$;

COMMENT ON FUNCTION tgsis.delete_version(text) IS
    'delete a version without children: its revisions, the row versions written in them, and its revisions in other rows'' lastrevs; returns the row versions removed';
