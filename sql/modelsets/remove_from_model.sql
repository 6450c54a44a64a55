-- tgsis.remove_from_model(name, objects): take objects out of a model (the objects stay); returns how many left it.
CREATE FUNCTION tgsis.remove_from_model(p_name text, p_objects bigint[])
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
    DELETE FROM tgsis.model_object mo WHERE mo.modelid = v_id AND mo.geoid = ANY (p_objects);
    GET DIAGNOSTICS v_count = ROW_COUNT;
    RETURN v_count;
END
$$;

COMMENT ON FUNCTION tgsis.remove_from_model(text, bigint[]) IS
    'remove objects from the model called name in the session''s version (the objects themselves stay); returns the number removed';
