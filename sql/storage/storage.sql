-- The plain-SQL route creates the storage tables here, where the table files
-- used to be, so that the SQL functions below (checked when created on this
-- route) find them. Inside CREATE EXTENSION (pg_extension has the row while
-- the script runs) it does not: tables created here would be extension members
-- that pg_dump leaves out; tgsis.install calls tgsis.create_storage() right
-- after CREATE EXTENSION instead (storage/create_storage.sql says why).
DO $do$
BEGIN
    IF NOT EXISTS (SELECT FROM pg_catalog.pg_extension WHERE extname = 'tgsis') THEN
        PERFORM tgsis.create_storage();
    END IF;
END
$do$;
