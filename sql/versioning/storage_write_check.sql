-- tgsis.storage_write_check(): statement trigger on every <table>_ver: direct writes need the write right on the session's version.
-- Reads and writes normally go through the view; the bulk path of the client
-- COPYs straight into storage (one trigger call per statement, not per row).
-- The table's owner and the owner of schema tgsis (whose SECURITY DEFINER
-- functions merge, refresh and compress) are not checked, as for RLS.
CREATE FUNCTION tgsis.storage_write_check()
RETURNS trigger
LANGUAGE plpgsql
VOLATILE
AS $$
BEGIN
    IF pg_catalog.pg_has_role(current_user, (SELECT relowner FROM pg_catalog.pg_class WHERE oid = TG_RELID), 'USAGE')
       OR pg_catalog.pg_has_role(current_user, (SELECT nspowner FROM pg_catalog.pg_namespace WHERE nspname = 'tgsis'), 'USAGE') THEN
        RETURN NULL;
    END IF;
    PERFORM tgsis.write_revision();  -- TG002 without the write right, TG301 while viewing; share-locks the version
    RETURN NULL;
END
$$;

COMMENT ON FUNCTION tgsis.storage_write_check() IS
    'BEFORE statement trigger of <table>_ver storage: a role other than the table''s or tgsis''s owner writing storage directly needs the write right on its session''s version (and not to be viewing an old revision)';
