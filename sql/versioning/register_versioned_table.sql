-- tgsis.register_versioned_table(view, ...): record in tgsis.versioned_tables a table enable_versioning has just versioned.
-- Definer functions (merges, deletes of versions, compress_versions,
-- disable_feature_versioning) act on what tgsis.versioned_tables names, as
-- tgsis's owner; only this function and tgsis's own definer code write it.
-- It records facts it checks in the system catalogs: <view> is a view with
-- tgsis's INSTEAD OF trigger calling <view>_ver_write(), over the table
-- <view>_ver of the same owner keyed by (key columns, revision); the calling
-- role owns them, or tgsis created them (tgsis.check_registrable). The object
-- class 'feature' is tgsis's own (model 1 and the feature classes).
CREATE FUNCTION tgsis.register_versioned_table(
    p_view           regclass,
    p_objectkeyfield text,
    p_objectclass    text,
    p_iudorder       integer,
    p_shortname      text,
    p_pkeyname       text,
    p_tablecomment   text,
    p_identity       text[])
RETURNS tgsis.versioned_tables
LANGUAGE plpgsql
VOLATILE
SECURITY DEFINER
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_expected text;
    v_schema text;
    v_table  text;
    v_kind   "char";
    v_owner  oid;
    v_ver    oid;
    v_keys   text[];
    v_tgsis  boolean;
    v_row    tgsis.versioned_tables;
BEGIN
    SELECT n.nspname, c.relname, c.relkind, c.relowner INTO v_schema, v_table, v_kind, v_owner
      FROM pg_class c JOIN pg_namespace n ON n.oid = c.relnamespace WHERE c.oid = p_view;
    SELECT c.oid INTO v_ver
      FROM pg_class c JOIN pg_namespace n ON n.oid = c.relnamespace
     WHERE n.nspname = v_schema AND c.relname = v_table || '_ver' AND c.relkind IN ('r', 'p') AND c.relowner = v_owner;
    IF v_kind IS DISTINCT FROM 'v' OR v_ver IS NULL
       OR NOT EXISTS (SELECT FROM pg_trigger tr JOIN pg_proc p ON p.oid = tr.tgfoid
                       WHERE tr.tgrelid = p_view AND tr.tgname = 'tgsis_versioning'
                         AND p.pronamespace = to_regnamespace(quote_ident(v_schema)) AND p.proname = v_table || '_ver_write')
       OR (SELECT count(*) FROM pg_attribute WHERE attrelid = v_ver AND NOT attisdropped
              AND attname IN ('revision', 'lastrevs', 'revclosed')) <> 3 THEN
        RAISE EXCEPTION '% is not a table versioned by tgsis.enable_versioning', coalesce(p_view::text, 'NULL')
            USING ERRCODE = 'TG100', HINT = 'tgsis.enable_versioning versions a table and registers it';
    END IF;
    PERFORM tgsis.check_registrable(v_schema, v_table, v_owner);
    IF EXISTS (SELECT FROM tgsis.versioned_tables WHERE schemaname = v_schema AND tablename = v_table) THEN
        RAISE EXCEPTION 'table %.% is versioned already', v_schema, v_table USING ERRCODE = 'TG201';
    END IF;
    v_tgsis := v_owner = (SELECT relowner FROM pg_class WHERE oid = 'tgsis.versioned_tables'::regclass)
               AND (v_schema = 'tgsis' OR EXISTS (SELECT FROM tgsis.class_tables c
                                                   WHERE c.schemaname = v_schema AND c.tablename = v_table));
    -- tgsis's storage is versioned in the object class its registry row names (tgsis.model_tables),
    -- feature-class tables with the features; those classes are tgsis's alone
    v_expected := CASE WHEN NOT v_tgsis THEN NULL
                       WHEN v_schema = 'tgsis' THEN (SELECT t.objectclass FROM tgsis.model_tables t WHERE t.tablename = v_table)
                       ELSE 'feature' END;
    IF v_expected IS NULL AND (p_objectclass = 'feature' OR EXISTS (SELECT FROM tgsis.model_tables t
                                                                     WHERE t.objectclass = p_objectclass)) THEN
        RAISE EXCEPTION 'object class ''%'' holds tgsis''s stored objects and the feature classes, not %.%', p_objectclass,
                v_schema, v_table
            USING ERRCODE = 'TG100',
                  HINT = 'give the table an object class of its own (tgsis.enable_feature_versioning versions the features)';
    ELSIF v_expected IS NOT NULL AND p_objectclass <> v_expected THEN
        RAISE EXCEPTION '%.% is versioned with the features, in object class ''%''', v_schema, v_table, v_expected
            USING ERRCODE = 'TG100', HINT = 'tgsis.enable_feature_versioning versions it';
    END IF;
    -- the row key: the storage's primary key without revision
    SELECT array_agg(a.attname::text ORDER BY k.ord) FILTER (WHERE a.attname <> 'revision') INTO v_keys
      FROM pg_constraint con
      CROSS JOIN LATERAL unnest(con.conkey) WITH ORDINALITY AS k(attnum, ord)
      JOIN pg_attribute a ON a.attrelid = con.conrelid AND a.attnum = k.attnum
     WHERE con.conrelid = v_ver AND con.contype = 'p' AND con.conname = v_table || '_ver_pkey';
    IF v_keys IS NULL
       OR p_objectkeyfield IS NULL
       OR NOT EXISTS (SELECT FROM pg_attribute WHERE attrelid = p_view AND attname = p_objectkeyfield AND NOT attisdropped)
       OR p_pkeyname IS NULL OR octet_length(p_pkeyname) > 63
       OR EXISTS (SELECT FROM unnest(coalesce(p_identity, '{}')) AS u(col)
                   WHERE NOT EXISTS (SELECT FROM pg_attribute WHERE attrelid = v_ver AND attname = u.col AND attidentity = 'd')) THEN
        RAISE EXCEPTION 'the key, object key field or identity columns given for %.% are not those of its storage', v_schema, v_table
            USING ERRCODE = 'TG100', HINT = 'tgsis.enable_versioning versions a table and registers it';
    END IF;
    IF p_objectclass IS NULL OR btrim(p_objectclass) = '' OR p_iudorder IS NULL THEN
        RAISE EXCEPTION 'versioning %.% needs an object class and an iudorder', v_schema, v_table USING ERRCODE = 'TG100';
    END IF;
    IF EXISTS (SELECT FROM tgsis.versioned_tables WHERE objectclass = p_objectclass AND shortname = coalesce(p_shortname, v_table)) THEN
        RAISE EXCEPTION 'object class % has a table with short name % already', quote_literal(p_objectclass),
                quote_literal(coalesce(p_shortname, v_table))
            USING ERRCODE = 'TG201', HINT = 'pass another p_shortname';
    END IF;
    -- what tgsis.storage_run relies on when it acts on the storage as tgsis's owner
    PERFORM tgsis.check_key_type(v_ver::regclass, p_objectkeyfield);
    IF NOT EXISTS (SELECT FROM pg_proc
                    WHERE oid = to_regprocedure(format('%I.%I(boolean, text, text[], integer[], integer[], integer, bigint[])',
                                                       v_schema, v_table || '_ver_run'))
                      AND prosecdef AND proowner = v_owner) THEN
        RAISE EXCEPTION '%.% has no runner %.%() of its owner', v_schema, v_table, v_schema, v_table || '_ver_run'
            USING ERRCODE = 'TG100', HINT = 'tgsis.enable_versioning versions a table and registers it';
    END IF;

    INSERT INTO tgsis.versioned_tables (schemaname, tablename, shortname, objectkeyfield, objectclass, iudorder,
                                        keycolumns, pkeyname, tablecomment, identity_always, enabled_by)
    VALUES (v_schema, v_table, coalesce(p_shortname, v_table), p_objectkeyfield, p_objectclass, p_iudorder,
            v_keys, p_pkeyname, p_tablecomment, coalesce(p_identity, '{}'), tgsis.calling_role())
    RETURNING * INTO v_row;
    RETURN v_row;
END
$$;

REVOKE ALL ON FUNCTION tgsis.register_versioned_table(regclass, text, text, integer, text, text, text, text[]) FROM PUBLIC;

COMMENT ON FUNCTION tgsis.register_versioned_table(regclass, text, text, integer, text, text, text, text[]) IS
    'record in tgsis.versioned_tables a table tgsis.enable_versioning has just versioned, after checking in the system catalogs that it is (view, trigger, <table>_ver storage) and that the calling role owns it or tgsis created it; object class ''feature'' is tgsis''s own';
