-- tgsis.storage_write_check(): BEFORE statement trigger on every <table>_ver: direct writes need the write right on the session's version.
-- Reads and writes normally go through the view; the bulk path of the client
-- COPYs straight into storage (one trigger call per statement, not per row).
-- Only INSERT is granted on storage to roles other than its owner (updates
-- and deletes go through the views and tgsis's functions); the rows an
-- INSERT writes are checked after it by tgsis.storage_rows_check. The
-- trigger's WHEN spares the table's owner (as whom the views' row triggers
-- write) and tgsis's owner (whose functions merge, refresh and compress).
-- Invoker's rights, so that current_user is the writer; the search_path is
-- pinned so that no object of the writer's can stand in for pg_catalog's.
CREATE FUNCTION tgsis.storage_write_check()
RETURNS trigger
LANGUAGE plpgsql
VOLATILE
SET search_path = pg_catalog, pg_temp
AS $$
BEGIN
    PERFORM tgsis.write_revision();  -- TG002 without the write right, TG301 while viewing; share-locks the version
    RETURN NULL;
END
$$;

COMMENT ON FUNCTION tgsis.storage_write_check() IS
    'BEFORE statement trigger of <table>_ver storage: a role other than the table''s or tgsis''s owner writing storage directly needs the write right on its session''s version (and not to be viewing an old revision)';
