-- tgsis.postgis_schema(): the schema PostGIS is installed in, or TG001 saying how to install it.
-- Why: PostGIS is optional. tgsis's script never names a PostGIS object (it
-- must install, upgrade and restore without PostGIS), so the functions that
-- need PostGIS find it at run time, wherever CREATE EXTENSION put it, and
-- reach it only through this schema name, quoted (format %I).
CREATE FUNCTION tgsis.postgis_schema()
RETURNS name
LANGUAGE plpgsql
STABLE
PARALLEL SAFE
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_schema name;
BEGIN
    SELECT n.nspname INTO v_schema
      FROM pg_catalog.pg_extension e JOIN pg_catalog.pg_namespace n ON n.oid = e.extnamespace
     WHERE e.extname = 'postgis';
    IF NOT FOUND THEN
        RAISE EXCEPTION 'PostGIS is not installed in database %', current_database()
            USING ERRCODE = 'TG001',
                  DETAIL = 'The PostGIS functions of tgsis (TIN Z, POLYHEDRALSURFACE Z) need the postgis extension.',
                  HINT = 'a role with the right may run: CREATE EXTENSION postgis; then SELECT tgsis.enable_postgis();';
    END IF;
    RETURN v_schema;
END
$$;

COMMENT ON FUNCTION tgsis.postgis_schema() IS
    'the schema of the postgis extension in this database; raises TG001 when PostGIS is not installed';
