-- tgsis.restore_dropped_constraints(): re-create the dropped constraints whose tables are all plain again; returns how many.
CREATE FUNCTION tgsis.restore_dropped_constraints()
RETURNS integer
LANGUAGE plpgsql
VOLATILE
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_item  tgsis.versioning_dropped;
    v_count integer := 0;
BEGIN
    FOR v_item IN
        SELECT d.* FROM tgsis.versioning_dropped d
         WHERE NOT EXISTS (SELECT FROM tgsis.versioned_tables t
                            WHERE (t.schemaname, t.tablename) IN ((d.schemaname, d.tablename), (d.refschema, d.reftable)))
         ORDER BY d.is_index DESC, d.id  -- unique indexes first: foreign keys may need them
    LOOP
        IF v_item.is_index THEN
            EXECUTE v_item.definition;  -- pg_get_indexdef text: a complete, qualified statement
        ELSE
            EXECUTE format('ALTER TABLE %I.%I ADD CONSTRAINT %I %s', v_item.schemaname, v_item.tablename, v_item.name,
                           v_item.definition);
        END IF;
        DELETE FROM tgsis.versioning_dropped WHERE id = v_item.id;
        v_count := v_count + 1;
    END LOOP;
    RETURN v_count;
END
$$;

COMMENT ON FUNCTION tgsis.restore_dropped_constraints() IS
    're-create constraints and unique indexes dropped by enable_versioning whose tables are no longer versioned; returns how many';
