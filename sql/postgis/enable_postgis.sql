-- tgsis.enable_postgis(): create the functions that return PostGIS geometries, once PostGIS is installed; returns PostGIS's schema.
-- Why created at run time and not by the extension script: their return type
-- is PostGIS's geometry, which exists only where PostGIS is installed, and
-- tgsis must install, upgrade and restore without it, and with PostGIS
-- installed before or after tgsis. Everything with substance is in the
-- script and needs no PostGIS (tgsis.ewkb_geometry, ewkb_geometry_at,
-- feature_srid); the functions made here are one-line wrappers around it
-- that name PostGIS's type and ST_GeomFromEWKB in PostGIS's schema (quoted).
-- Created after CREATE EXTENSION, they are no extension members on either
-- install route: pg_dump dumps them whole, after CREATE EXTENSION postgis
-- (they depend on its type), like the storage tables (docs/install.md,
-- "Backup and restore"; docs/postgis.md). Never call this from an extension
-- script (the wrappers would become members and vanish from dumps);
-- tgsis.install calls it again after an upgrade when they exist.
-- It runs as tgsis's owner, who owns schema tgsis, for members of tgsis_admin.
CREATE FUNCTION tgsis.enable_postgis()
RETURNS name
LANGUAGE plpgsql
VOLATILE
SECURITY DEFINER
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_ps name;
BEGIN
    IF NOT pg_has_role(tgsis.calling_role(), 'tgsis_admin', 'MEMBER') THEN
        RAISE EXCEPTION 'role % may not enable the PostGIS functions of tgsis', tgsis.calling_role()
            USING ERRCODE = 'TG002', DETAIL = 'Creating functions in schema tgsis is for members of tgsis_admin.',
                  HINT = format('a DBA may run: GRANT tgsis_admin TO %I; or ask one to run SELECT tgsis.enable_postgis()',
                                tgsis.calling_role());
    END IF;
    v_ps := tgsis.postgis_schema();
    EXECUTE format($f$
        CREATE OR REPLACE FUNCTION tgsis.postgis_geometry(p_class text, p_geoid bigint)
        RETURNS %1$I.geometry
        LANGUAGE sql
        STABLE
        PARALLEL SAFE
        AS $body$ SELECT %1$I.st_geomfromewkb(tgsis.ewkb_geometry(p_geoid, tgsis.feature_srid(p_class, p_geoid))) $body$
        $f$, v_ps);
    EXECUTE format($f$
        CREATE OR REPLACE FUNCTION tgsis.postgis_geometry_at(p_class text, p_geoid bigint, p_t double precision,
                                                             p_convention text DEFAULT 'left')
        RETURNS %1$I.geometry
        LANGUAGE sql
        STABLE
        PARALLEL SAFE
        AS $body$
            SELECT %1$I.st_geomfromewkb(tgsis.ewkb_geometry_at(p_geoid, p_t, p_convention, tgsis.feature_srid(p_class, p_geoid)))
        $body$
        $f$, v_ps);
    COMMENT ON FUNCTION tgsis.postgis_geometry(text, bigint) IS
        'a feature of a static class as a PostGIS geometry with the class''s SRS as SRID: SURFACE as TIN Z, MULTITETRA as the POLYHEDRALSURFACE Z of its boundary, MULTILINESTRING Z, MULTIPOINT Z, GEOMETRYCOLLECTION Z (created by tgsis.enable_postgis)';
    COMMENT ON FUNCTION tgsis.postgis_geometry_at(text, bigint, double precision, text) IS
        'a feature''s shape at model time t as a PostGIS geometry (a temporal surface: TIN Z of its snapshot), NULL when it does not exist at t (created by tgsis.enable_postgis)';
    RETURN v_ps;
END
$$;

REVOKE ALL ON FUNCTION tgsis.enable_postgis() FROM PUBLIC;
GRANT EXECUTE ON FUNCTION tgsis.enable_postgis() TO tgsis_admin;

COMMENT ON FUNCTION tgsis.enable_postgis() IS
    'create tgsis.postgis_geometry(class, geoid) and tgsis.postgis_geometry_at(class, geoid, t, convention), which return PostGIS geometries, once PostGIS is installed (TG001 otherwise); returns PostGIS''s schema. For tgsis_admin; run it again after PostGIS moves';
