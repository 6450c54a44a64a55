-- tgsis.create_versioned_view(schema, table, keys, pkey, object class, object key, grants, comment): the view of a versioned table.
-- What stands in a versioned table's place: the view <table> over the storage
-- <table>_ver (its columns but revision, lastrevs and revclosed, with their
-- defaults and comments), the INSTEAD OF trigger function <table>_ver_write()
-- generated for exactly those columns, the triggers, the grants and the owner
-- (the storage's). tgsis.enable_versioning_rel creates it once; after the
-- columns of the storage changed (tgsis.add_property, rename_property,
-- drop_property) the caller drops the view and its trigger function and
-- creates them again here, so that writes through the view carry the new
-- columns. Runs with the caller's rights: the caller acts as the storage's
-- owner.
CREATE FUNCTION tgsis.create_versioned_view(
    p_schema      text,
    p_table       text,
    p_keys        text[],
    p_pkey        text,
    p_objectclass text,
    p_keyfield    text,
    p_grants      aclitem[],
    p_comment     text)
RETURNS void
LANGUAGE plpgsql
VOLATILE
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_ver      regclass := format('%I.%I', p_schema, p_table || '_ver')::regclass;
    v_owner    oid := (SELECT c.relowner FROM pg_class c WHERE c.oid = format('%I.%I', p_schema, p_table || '_ver')::regclass);
    v_columns  text[];
    v_writable text[];
    v_col      record;
    v_acl      record;
    v_geoid    text;
BEGIN
    SELECT array_agg(attname::text ORDER BY attnum), array_agg(attname::text ORDER BY attnum) FILTER (WHERE attgenerated = '')
      INTO v_columns, v_writable
      FROM pg_attribute WHERE attrelid = v_ver AND attnum > 0 AND NOT attisdropped
       AND attname NOT IN ('revision', 'lastrevs', 'revclosed');
    -- a model table every feature class shares (tgsis.model_tables): the view reads its storage as the
    -- owner, whom row-level security spares, so it filters by the reader's class rights itself, the
    -- filter the storage's policies apply (tgsis.protect_model_tables), as a security barrier (no
    -- function of the reader's query sees a row first). The view's source ends with its WHERE clause.
    SELECT t.geoidcolumn INTO v_geoid FROM tgsis.model_tables t
     WHERE p_schema = 'tgsis' AND t.tablename = p_table AND t.geoidcolumn IS NOT NULL;
    EXECUTE tgsis.versioned_view_source(p_schema, p_table, v_columns)
            || CASE WHEN v_geoid IS NOT NULL
                    THEN ' AND ' || tgsis.class_rights_filter(v_geoid, 'SELECT', 'v') ELSE '' END;
    IF v_geoid IS NOT NULL THEN
        EXECUTE format('ALTER VIEW %I.%I SET (security_barrier = true)', p_schema, p_table);
    END IF;
    FOR v_col IN
        SELECT a.attname,
               CASE WHEN a.attidentity <> '' THEN format('nextval(%L::regclass)', pg_get_serial_sequence(v_ver::text, a.attname))
                    ELSE pg_get_expr(d.adbin, d.adrelid) END AS expr,
               col_description(v_ver, a.attnum) AS note
          FROM pg_attribute a LEFT JOIN pg_attrdef d ON d.adrelid = a.attrelid AND d.adnum = a.attnum
         WHERE a.attrelid = v_ver AND a.attnum > 0 AND NOT a.attisdropped AND a.attname::text = ANY (v_columns)
    LOOP
        IF v_col.expr IS NOT NULL AND v_col.attname::text = ANY (v_writable) THEN
            -- a deparsed default from the catalog: SQL text, not a value to quote
            EXECUTE format('ALTER VIEW %I.%I ALTER COLUMN %I SET DEFAULT %s', p_schema, p_table, v_col.attname, v_col.expr);
        END IF;
        IF v_col.note IS NOT NULL THEN
            EXECUTE format('COMMENT ON COLUMN %I.%I.%I IS %L', p_schema, p_table, v_col.attname, v_col.note);
        END IF;
    END LOOP;
    EXECUTE format('COMMENT ON VIEW %I.%I IS %L', p_schema, p_table, p_comment);
    FOR v_acl IN
        SELECT a.privilege_type, a.grantee, a.is_grantable FROM aclexplode(p_grants) AS a WHERE a.grantee <> v_owner
    LOOP
        -- (grant options kept: a role that could pass a right on the table can pass it on the view)
        EXECUTE format('GRANT %s ON %I.%I TO %s%s', v_acl.privilege_type, p_schema, p_table,
                       CASE WHEN v_acl.grantee = 0 THEN 'PUBLIC' ELSE quote_ident(pg_get_userbyid(v_acl.grantee)) END,
                       CASE WHEN v_acl.is_grantable THEN ' WITH GRANT OPTION' ELSE '' END);
    END LOOP;
    PERFORM tgsis.create_versioning_trigger(p_schema, p_table, p_keys, p_pkey, p_objectclass, p_keyfield);
    EXECUTE format('CREATE TRIGGER tgsis_versioning_rights BEFORE INSERT OR UPDATE OR DELETE ON %I.%I '
                   'FOR EACH STATEMENT EXECUTE FUNCTION tgsis.view_write_check()', p_schema, p_table);
    EXECUTE format('ALTER VIEW %I.%I OWNER TO %I', p_schema, p_table, pg_get_userbyid(v_owner));
END
$$;

COMMENT ON FUNCTION tgsis.create_versioned_view(text, text, text[], text, text, text, aclitem[], text) IS
    'create the view <table> over <table>_ver (its columns but revision, lastrevs, revclosed, with defaults and comments), its generated INSTEAD OF trigger function <table>_ver_write(), triggers, grants (p_grants, an ACL) and owner (the storage''s); used by enable_versioning_rel and after a change of the storage''s columns';
