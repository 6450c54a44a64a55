-- tgsis.model_objects(name): the objects of a model in the session's version, with their feature class and name.
CREATE FUNCTION tgsis.model_objects(p_name text)
RETURNS TABLE (geoid bigint, classname text, geoname text)
LANGUAGE plpgsql
STABLE
SET search_path FROM CURRENT
AS $$
DECLARE
    v_id bigint := tgsis.model_id(p_name);
BEGIN
    PERFORM tgsis.require_storage();  -- a bare CREATE EXTENSION: say what to run (geometry/require_storage.sql)
    RETURN QUERY
    SELECT mo.geoid, c.classname, g.geoname
      FROM tgsis.model_object mo
      JOIN tgsis.geometry g ON g.geoid = mo.geoid
      LEFT JOIN LATERAL (SELECT ct.classname FROM tgsis.catalog ct
                          WHERE ct.geotype = g.geotype AND ct.timemodel = g.timemodel
                            AND tgsis.feature_of_class(ct.classname, mo.geoid)
                          ORDER BY ct.classname LIMIT 1) c ON true
     WHERE mo.modelid = v_id
     ORDER BY mo.geoid;
END
$$;

COMMENT ON FUNCTION tgsis.model_objects(text) IS
    'the objects (geoid, their feature class, their name) of the model called name in the session''s version, by id';
