-- tgsis.create_change_trigger(schema, table, object key column): the trigger of <table>_ver that notes direct writes in tgsis.revision_objects.
-- Called by tgsis.enable_versioning_rel, and by the upgrade that brought
-- tgsis.revision_objects for tables versioned before it. Its WHEN leaves
-- out the storage's owner writing inside a trigger: the views' INSTEAD OF
-- triggers, which run as that owner and note their objects themselves
-- (tgsis.record_inserted_objects says why). The owner is named, not given
-- by oid: a dump restored into another cluster keeps role names. Runs with
-- the caller's rights: the caller acts as the storage's owner.
CREATE FUNCTION tgsis.create_change_trigger(p_schema text, p_table text, p_keyfield text)
RETURNS void
LANGUAGE plpgsql
VOLATILE
SET search_path = pg_catalog, pg_temp
AS $$
BEGIN
    EXECUTE format('CREATE TRIGGER tgsis_storage_changes AFTER INSERT ON %I.%I REFERENCING NEW TABLE AS tgsis_new_rows '
                   'FOR EACH STATEMENT WHEN (pg_catalog.pg_trigger_depth() = 0 OR CURRENT_USER <> %L::name) '
                   'EXECUTE FUNCTION tgsis.record_inserted_objects(%L)',
                   p_schema, p_table || '_ver',
                   (SELECT pg_get_userbyid(c.relowner) FROM pg_class c
                     WHERE c.oid = format('%I.%I', p_schema, p_table || '_ver')::regclass),
                   p_keyfield);
END
$$;

COMMENT ON FUNCTION tgsis.create_change_trigger(text, text, text) IS
    'create the trigger tgsis_storage_changes of <table>_ver: direct inserts into storage note their objects in tgsis.revision_objects (tgsis.record_inserted_objects)';
