-- tgsis.add_to_model(name, objects): put stored objects into a model (those already in it stay); returns how many were added.
-- An object may belong to several models; the membership is a row of the
-- object's (versioned with it, deleted with it).
CREATE FUNCTION tgsis.add_to_model(p_name text, p_objects bigint[])
RETURNS bigint
LANGUAGE plpgsql
VOLATILE
SET search_path FROM CURRENT
AS $$
DECLARE
    v_id    bigint;
    v_count bigint;
BEGIN
    PERFORM tgsis.require_storage();  -- a bare CREATE EXTENSION: say what to run (geometry/require_storage.sql)
    PERFORM tgsis.plain_write_check('tgsis', 'model_object');
    v_id := tgsis.model_id(p_name);
    INSERT INTO tgsis.model_object (geoid, modelid)
    SELECT o, v_id FROM unnest(tgsis.checked_objects(p_objects)) o
     WHERE NOT EXISTS (SELECT FROM tgsis.model_object mo WHERE mo.geoid = o AND mo.modelid = v_id);
    GET DIAGNOSTICS v_count = ROW_COUNT;
    RETURN v_count;
END
$$;

COMMENT ON FUNCTION tgsis.add_to_model(text, bigint[]) IS
    'add stored objects to the model called name in the session''s version (members stay members); returns the number added';
