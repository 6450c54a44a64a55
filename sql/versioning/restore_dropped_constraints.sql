-- tgsis.restore_dropped_constraints(schema, table): re-create the dropped constraints of, or referring to, a table just made plain; returns how many.
-- Called by disable_versioning_rel, as the role making the table plain
-- (tgsis's owner within disable_feature_versioning). It restores only rows
-- about that table whose tables are all plain again; the definitions are
-- system-catalog text that tgsis.record_dropped (or tgsis's own definer code)
-- wrote, as nobody else may write tgsis.versioning_dropped. A constraint that
-- exists already is only forgotten; one on a table the role may not alter
-- stays recorded (NOTICE) for its owner's disable_versioning to restore.
CREATE FUNCTION tgsis.restore_dropped_constraints(p_schema text, p_table text)
RETURNS integer
LANGUAGE plpgsql
VOLATILE
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_item  tgsis.versioning_dropped;
    v_rel   regclass;
    v_count integer := 0;
BEGIN
    FOR v_item IN
        SELECT d.* FROM tgsis.versioning_dropped d
         WHERE ((d.schemaname = p_schema AND d.tablename = p_table) OR (d.refschema = p_schema AND d.reftable = p_table))
           AND NOT EXISTS (SELECT FROM tgsis.versioned_tables t
                            WHERE (t.schemaname, t.tablename) IN ((d.schemaname, d.tablename), (d.refschema, d.reftable)))
         ORDER BY d.is_index DESC, d.id  -- unique indexes first: foreign keys may need them
    LOOP
        IF tgsis.forget_dropped(v_item.id) THEN
            CONTINUE;  -- it is there (recorded but never dropped)
        END IF;
        v_rel := to_regclass(format('%I.%I', v_item.schemaname, v_item.tablename));
        IF v_rel IS NULL OR NOT pg_has_role(current_user, (SELECT relowner FROM pg_class WHERE oid = v_rel), 'USAGE') THEN
            RAISE NOTICE 'constraint % of %.% stays dropped: role % may not alter that table',
                    v_item.name, v_item.schemaname, v_item.tablename, current_user
                USING HINT = 'its owner restores it with tgsis.restore_dropped_constraints(schema, table)';
            CONTINUE;
        END IF;
        IF v_item.is_index THEN
            EXECUTE v_item.definition;  -- pg_get_indexdef text: a complete, qualified statement
        ELSE
            EXECUTE format('ALTER TABLE %I.%I ADD CONSTRAINT %I %s', v_item.schemaname, v_item.tablename, v_item.name,
                           v_item.definition);
        END IF;
        PERFORM tgsis.forget_dropped(v_item.id);
        v_count := v_count + 1;
    END LOOP;
    RETURN v_count;
END
$$;

COMMENT ON FUNCTION tgsis.restore_dropped_constraints(text, text) IS
    're-create the constraints and unique indexes dropped by enable_versioning that belong to or refer to a table made plain again, once all their tables are plain; returns how many';
