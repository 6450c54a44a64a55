-- tgsis.version(): the version of the tgsis objects installed in this database.
CREATE FUNCTION tgsis.version()
RETURNS text
LANGUAGE sql
IMMUTABLE
PARALLEL SAFE
AS $$ SELECT '@TGSIS_VERSION@'::text $$;

COMMENT ON FUNCTION tgsis.version() IS
    'version of the tgsis SQL objects installed in this database (the same as the Python client''s tgsis.__version__ when they match)';
