-- First start of the container: PostGIS and tgsis in the POSTGRES_DB database.
CREATE EXTENSION IF NOT EXISTS postgis;
CREATE EXTENSION IF NOT EXISTS tgsis CASCADE;
-- the tables of stored objects are no extension members (docs/install.md, "Backup and restore")
SELECT tgsis.create_storage();
-- tgsis's functions that return PostGIS geometries (docs/postgis.md)
SELECT tgsis.enable_postgis();
