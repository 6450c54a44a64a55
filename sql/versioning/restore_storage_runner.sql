-- tgsis.restore_storage_runner(table): give a versioned table its runner back, for its owner.
CREATE FUNCTION tgsis.restore_storage_runner(p_table regclass)
RETURNS void
LANGUAGE plpgsql
VOLATILE
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_t tgsis.versioned_tables := tgsis.versioned_table(p_table);
BEGIN
    PERFORM tgsis.create_storage_runner(v_t.schemaname, v_t.tablename);
END
$$;

COMMENT ON FUNCTION tgsis.restore_storage_runner(regclass) IS
    'for the owner of a versioned table: re-create its runner <table>_ver_run() (after it was dropped or altered, or the storage changed owner), so that merges and deletes of versions act on it again';
