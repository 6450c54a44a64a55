-- tgsis.require_storage(): refuse, with what to run, when tgsis's storage tables do not exist.
-- CREATE EXTENSION tgsis makes the functions and the catalog, not the tables of stored objects:
-- those come from tgsis.create_storage() (storage/create_storage.sql says why), which tgsis db install
-- runs after CREATE EXTENSION. A database where someone ran only CREATE EXTENSION used to fail at
-- the first class with a raw "relation tgsis.geometry does not exist"; every entry point that needs
-- the storage (registering a class, making a geometry or a model, versioning features, deleting,
-- partitioning) calls this first. Every data model stores its geometries' rows in tgsis.geometry
-- too, and tgsis.create_storage() makes the tables of all registered models at once (a model with
-- only some of its tables is refused there), so that one table stands for all of them.
CREATE FUNCTION tgsis.require_storage()
RETURNS void
LANGUAGE plpgsql
STABLE
PARALLEL SAFE
SET search_path = pg_catalog, pg_temp
AS $require$
BEGIN
    IF to_regclass('tgsis.geometry') IS NULL THEN
        RAISE EXCEPTION 'tgsis''s storage tables do not exist in this database (tgsis.geometry and the tables of the data models)'
            USING ERRCODE = 'TG001',
                  DETAIL = 'CREATE EXTENSION tgsis creates the functions and the catalog; the storage tables are made by '
                           'tgsis.create_storage(), so that pg_dump dumps them whole (docs/install.md, "Backup and restore").',
                  HINT = 'As tgsis''s owner run SELECT tgsis.create_storage(); (or tgsis db install, which does it).';
    END IF;
END
$require$;

COMMENT ON FUNCTION tgsis.require_storage() IS
    'raise TG001 naming tgsis.create_storage() when the storage tables do not exist (a bare CREATE EXTENSION tgsis); called first by the entry points that need them';
