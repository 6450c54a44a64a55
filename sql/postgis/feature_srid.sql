-- tgsis.feature_srid(class, geoid): the SRID of a feature of a class (the class's SRS), or TG200 naming what is missing.
-- Why: a geometry row does not know its class, and PostGIS geometries carry
-- their SRID, which is the class's srs (tgsis.catalog). Checking that the
-- feature is one of the class's also keeps a wrong pair (class, id) from
-- giving a geometry the SRID of another class. The feature table is read as
-- the caller, through its name (under feature versioning: the caller's version).
CREATE FUNCTION tgsis.feature_srid(p_class text, p_geoid bigint)
RETURNS integer
LANGUAGE plpgsql
STABLE
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_class tgsis.catalog := tgsis.catalog_row(p_class);
    v_found boolean;
BEGIN
    EXECUTE format('SELECT EXISTS (SELECT FROM %I.%I WHERE _geoid = $1)', v_class.schemaname, v_class.featuretable)
       INTO v_found USING p_geoid;
    IF NOT v_found THEN
        RAISE EXCEPTION 'feature % of class % does not exist', coalesce(p_geoid::text, 'NULL'), p_class
            USING ERRCODE = 'TG200', HINT = format('SELECT _geoid FROM %I.%I lists its features', v_class.schemaname,
                                                   v_class.featuretable);
    END IF;
    RETURN v_class.srs;
END
$$;

COMMENT ON FUNCTION tgsis.feature_srid(text, bigint) IS
    'the SRID (the class''s srs) of a feature of a class; raises TG200 when the class or the feature does not exist';
