-- The tgsis schema holds every object of the extension.
-- CREATE EXTENSION creates it from the control file's `schema` (and does not
-- make it an extension member, so CREATE SCHEMA IF NOT EXISTS would be refused
-- in this script); the plain-SQL install (tgsis.install) must create it here.
DO $do$
BEGIN
    IF to_regnamespace('tgsis') IS NULL THEN
        CREATE SCHEMA tgsis;
    END IF;
END
$do$;

COMMENT ON SCHEMA tgsis IS
    'tgsis: spatio-temporal geoscience information system (geological objects with topology, properties, time and versions)';
