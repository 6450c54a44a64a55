-- tgsis.feature_of_class(class, geoid): whether the class's feature table has the feature (through its name: the session's version).
CREATE FUNCTION tgsis.feature_of_class(p_class text, p_geoid bigint)
RETURNS boolean
LANGUAGE plpgsql
STABLE
SET search_path FROM CURRENT
AS $$
DECLARE
    v_class tgsis.catalog := tgsis.catalog_row(p_class);
    v_found boolean;
BEGIN
    EXECUTE format('SELECT EXISTS (SELECT FROM %I.%I WHERE _geoid = $1)', v_class.schemaname, v_class.featuretable)
       INTO v_found USING p_geoid;
    RETURN v_found;
END
$$;

COMMENT ON FUNCTION tgsis.feature_of_class(text, bigint) IS 'whether feature class p_class has the feature p_geoid in the session''s version';
