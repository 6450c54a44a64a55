-- tgsis.record_dropped(table, object, is_index): record, before enable_versioning drops it, a constraint or unique index that cannot hold across versions.
-- tgsis.versioning_dropped is written only here (and by tgsis's own definer
-- code): restore_dropped_constraints EXECUTEs what it holds. So the caller
-- gives only the object's oid, and the definition is read from the system
-- catalogs (pg_get_constraintdef / pg_get_indexdef with a search_path of
-- pg_catalog alone, so qualified); the object must belong to, or refer to,
-- the table being versioned, a plain table the calling role owns (or one tgsis
-- created). A row recorded for an object that is then not dropped is
-- harmless: restore_dropped_constraints finds it present and forgets it.
CREATE FUNCTION tgsis.record_dropped(p_table regclass, p_object oid, p_is_index boolean DEFAULT false)
RETURNS integer
LANGUAGE plpgsql
VOLATILE
SECURITY DEFINER
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_schema text;
    v_name   text;
    v_kind   "char";
    v_owner  oid;
    v_id     integer;
BEGIN
    SELECT n.nspname, c.relname, c.relkind, c.relowner INTO v_schema, v_name, v_kind, v_owner
      FROM pg_class c JOIN pg_namespace n ON n.oid = c.relnamespace WHERE c.oid = p_table;
    IF v_kind IS NULL OR v_kind NOT IN ('r', 'p')
       OR EXISTS (SELECT FROM tgsis.versioned_tables WHERE schemaname = v_schema AND tablename = v_name) THEN
        RAISE EXCEPTION 'constraints are recorded only for a plain table about to be versioned, not %',
                coalesce(p_table::text, 'NULL')
            USING ERRCODE = 'TG100', HINT = 'tgsis.enable_versioning records what it drops';
    END IF;
    PERFORM tgsis.check_registrable(v_schema, v_name, v_owner);

    IF coalesce(p_is_index, false) THEN
        INSERT INTO tgsis.versioning_dropped (schemaname, tablename, name, definition, is_index, dropped_for)
        SELECT v_schema, v_name, c.relname, pg_get_indexdef(i.indexrelid), true, format('%I.%I', v_schema, v_name)
          FROM pg_index i JOIN pg_class c ON c.oid = i.indexrelid
         WHERE i.indexrelid = p_object AND i.indrelid = p_table AND i.indisunique
           AND NOT EXISTS (SELECT FROM pg_constraint con WHERE con.conindid = i.indexrelid)
        RETURNING id INTO v_id;
    ELSE
        -- a constraint of another versioned table is recorded under its plain name
        INSERT INTO tgsis.versioning_dropped (schemaname, tablename, name, definition, refschema, reftable, dropped_for)
        SELECT n.nspname, coalesce(t.tablename, c.relname), con.conname, pg_get_constraintdef(con.oid), rn.nspname,
               rc.relname, format('%I.%I', v_schema, v_name)
          FROM pg_constraint con
          JOIN pg_class c ON c.oid = con.conrelid JOIN pg_namespace n ON n.oid = c.relnamespace
          LEFT JOIN tgsis.versioned_tables t ON t.schemaname = n.nspname AND t.tablename || '_ver' = c.relname
          LEFT JOIN pg_class rc ON rc.oid = con.confrelid LEFT JOIN pg_namespace rn ON rn.oid = rc.relnamespace
         WHERE con.oid = p_object AND con.contype IN ('u', 'x', 'f')
           AND (con.conrelid = p_table OR (con.contype = 'f' AND con.confrelid = p_table))
        RETURNING id INTO v_id;
    END IF;
    IF v_id IS NULL THEN
        RAISE EXCEPTION '% is not a % of %', p_object,
                CASE WHEN p_is_index THEN 'unique index (outside constraints)' ELSE 'unique, exclusion or foreign-key constraint' END,
                p_table
            USING ERRCODE = 'TG200';
    END IF;
    RETURN v_id;
END
$$;

REVOKE ALL ON FUNCTION tgsis.record_dropped(regclass, oid, boolean) FROM PUBLIC;

COMMENT ON FUNCTION tgsis.record_dropped(regclass, oid, boolean) IS
    'record in tgsis.versioning_dropped a constraint (or unique index) of, or referring to, a plain table the calling role owns, its definition read from the system catalogs, before enable_versioning drops it; returns the row id';
