-- Rights of the group roles on the core objects. Later files grant on their
-- own objects; this one only opens the schema and the core catalog.
GRANT USAGE ON SCHEMA tgsis TO tgsis_reader;
GRANT SELECT ON tgsis.error_codes, tgsis.installation TO tgsis_reader;
GRANT EXECUTE ON FUNCTION tgsis.version() TO tgsis_reader;
