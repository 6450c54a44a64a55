-- tgsis.alter_class_table(class, table, alters, properties, what): ALTER TABLE one table of a feature class, versioned or not.
-- A plain table is altered in place. A versioned one is altered in its
-- storage <table>_ver, whose rows are every version's: a column added there
-- is added in every version, a renamed one keeps its values in every
-- version. Its view and the trigger function generated for its columns are
-- then made again (tgsis.create_versioned_view), with the view's grants and
-- comment, so that writes through the view carry the new columns; merges,
-- refreshes and check-ins read the storage's columns when they run. The
-- columns of p_properties are commented (comment_property_columns) before the
-- views are made, which copy the comments. The
-- class view <class>_v (with the rights granted on it) and the PostGIS view
-- <class>_postgis, if tgsis.create_postgis_view made one, are made again over
-- the new columns.
-- Views of others over the class's tables would read a column that changed:
-- they are refused (TG202), nothing changed. Runs as the owner of the
-- class's tables (tgsis's): called by add_property, rename_property and
-- drop_property. A property table stored in chunks (tgsis.store_class_in_chunks),
-- versioned or not, is altered in place (tgsis.alter_chunk_table): the ALTERs
-- on its row definition <table>_shape, the chunk table's arrays added (the
-- default at present slots, NULL at holes, in every chunk version), renamed or
-- dropped, the chunk view and the face made again with the face's grants and
-- the columns' comments;
-- what the chunks cannot hold (a reserved name, no property left) is
-- refused by name (TG100), nothing changed; a vector property is added or
-- renamed in place too.
-- A versioned table's conflicts' marks are renewed, in rows as in chunks
-- (tgsis.conflict_marks before, tgsis.renew_conflict_marks after): a column
-- added or dropped changes the stored rows' fingerprints without changing a
-- value either side chose, so solved conflicts stay solved; a later edit
-- unsolves them as before.
CREATE FUNCTION tgsis.alter_class_table(p_class tgsis.catalog, p_table text, p_alters text[],
                                        p_properties jsonb DEFAULT '[]', p_what text DEFAULT NULL)
RETURNS void
LANGUAGE plpgsql
VOLATILE
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_schema  text := p_class.schemaname;
    v_t       tgsis.versioned_tables;
    v_view    regclass;
    v_grants  aclitem[];
    v_comment text;
    v_detail  text;
    v_alter   text;
    v_class_grants aclitem[];
    v_acl     record;
    v_chunked boolean;
    v_marks   jsonb;
BEGIN
    -- a property table stored in chunks (tgsis.store_class_in_chunks): its columns are the chunk table's arrays and
    -- the face's; it is altered in place (tgsis.alter_chunk_table)
    v_chunked := to_regclass(format('%I.%I', v_schema, p_table || '_shape')) IS NOT NULL
                 AND to_regclass(format('%I.%I', v_schema, p_table || '_chunk')) IS NOT NULL
                 AND (SELECT c.relkind FROM pg_class c WHERE c.oid = to_regclass(format('%I.%I', v_schema, p_table))) = 'v';
    IF EXISTS (SELECT FROM tgsis.versioned_tables t WHERE t.schemaname = v_schema AND t.tablename = p_table) THEN
        -- the conflicts' marks fingerprint the stored row versions (record_out of each <table>_ver row) or chunk
        -- versions, which a new or dropped column changes without changing a value either side of a conflict
        -- chose: read before, renewed after, in both storages (solved conflicts stay solved)
        v_marks := tgsis.conflict_marks();
    END IF;
    -- the class view is made again by tgsis.create_class_view; the rights granted on it since are kept
    SELECT c.relacl INTO v_class_grants FROM pg_class c
     WHERE c.oid = to_regclass(format('%I.%I', v_schema, p_class.viewname));
    BEGIN
        EXECUTE format('DROP VIEW IF EXISTS %I.%I', v_schema, p_class.viewname);
        SELECT * INTO v_t FROM tgsis.versioned_tables t WHERE t.schemaname = v_schema AND t.tablename = p_table;
        IF v_chunked THEN
            PERFORM tgsis.alter_chunk_table(format('%I.%I', v_schema, p_table), p_alters, p_properties, p_what);
        ELSIF NOT FOUND THEN
            FOREACH v_alter IN ARRAY p_alters LOOP
                EXECUTE format('ALTER TABLE %I.%I %s', v_schema, p_table, v_alter);
            END LOOP;
            PERFORM tgsis.comment_property_columns(v_schema, p_table, p_properties, p_what);
        ELSE
            v_view := format('%I.%I', v_schema, p_table)::regclass;
            SELECT c.relacl, obj_description(c.oid, 'pg_class') INTO v_grants, v_comment FROM pg_class c WHERE c.oid = v_view;
            EXECUTE format('DROP VIEW %s', v_view);   -- (its triggers with it)
            EXECUTE format('DROP FUNCTION %I.%I()', v_schema, p_table || '_ver_write');
            EXECUTE format('DROP TABLE %I.%I', v_schema, p_table || '_ver_queue');
            FOREACH v_alter IN ARRAY p_alters LOOP
                EXECUTE format('ALTER TABLE %I.%I %s', v_schema, p_table || '_ver', v_alter);
            END LOOP;
            PERFORM tgsis.comment_property_columns(v_schema, p_table || '_ver', p_properties, p_what);
            PERFORM tgsis.create_versioned_view(v_schema, p_table, v_t.keycolumns, v_t.pkeyname, v_t.objectclass,
                                                v_t.objectkeyfield, v_grants, v_comment);
        END IF;
    EXCEPTION WHEN dependent_objects_still_exist THEN
        GET STACKED DIAGNOSTICS v_detail = PG_EXCEPTION_DETAIL;
        RAISE EXCEPTION 'other objects depend on table %.% of feature class %', v_schema, p_table, p_class.classname
            USING ERRCODE = 'TG202', DETAIL = v_detail,
                  HINT = 'drop the views that read the class''s tables, change the class, then create them again';
    END;
    IF v_marks IS NOT NULL THEN
        PERFORM tgsis.renew_conflict_marks(v_marks);
    END IF;
    PERFORM tgsis.create_class_view(p_class.classname);
    FOR v_acl IN
        SELECT a.privilege_type, a.grantee FROM aclexplode(v_class_grants) AS a
         WHERE a.grantee <> (SELECT c.relowner FROM pg_class c WHERE c.oid = format('%I.%I', v_schema, p_class.viewname)::regclass)
    LOOP
        EXECUTE format('GRANT %s ON %I.%I TO %s', v_acl.privilege_type, v_schema, p_class.viewname,
                       CASE WHEN v_acl.grantee = 0 THEN 'PUBLIC' ELSE quote_ident(pg_get_userbyid(v_acl.grantee)) END);
    END LOOP;
    -- a PostGIS view tgsis made (as tgsis.drop_feature_class recognises it) lists the feature table's columns
    IF (SELECT obj_description(c.oid, 'pg_class') LIKE 'tgsis PostGIS view %' AND c.relkind = 'v'
               AND c.relowner = (SELECT relowner FROM pg_class WHERE oid = 'tgsis.catalog'::regclass)
          FROM pg_class c WHERE c.oid = to_regclass(format('%I.%I', v_schema, p_class.classname || '_postgis'))) THEN
        PERFORM tgsis.create_postgis_view(p_class.classname);
    END IF;
END
$$;

COMMENT ON FUNCTION tgsis.alter_class_table(tgsis.catalog, text, text[], jsonb, text) IS
    'run ALTER TABLE <each of p_alters> on a feature-class table (in place when plain, on <table>_ver when versioned: every version''s rows; in place on its chunk table, every chunk version, when its properties are in chunks: tgsis.alter_chunk_table), re-create its versioned view and generated trigger function over the new columns, and the class view (and PostGIS view); TG202 when views of others depend on it';
