-- tgsis.model_id(name): the id of the model called name in the session's version; TG200 naming it when there is none.
-- Models are named sets of objects (tgsis.model); the writers and readers
-- below take a name, as people do.
CREATE FUNCTION tgsis.model_id(p_name text)
RETURNS bigint
LANGUAGE plpgsql
STABLE
SET search_path FROM CURRENT
AS $$
DECLARE
    v_id bigint;
BEGIN
    PERFORM tgsis.require_storage();  -- a bare CREATE EXTENSION: say what to run (geometry/require_storage.sql)
    SELECT m.modelid INTO v_id FROM tgsis.model m WHERE m.name = p_name;
    IF NOT FOUND THEN
        RAISE EXCEPTION 'model % does not exist in version %', coalesce(quote_literal(p_name), 'NULL'),
                        quote_literal(tgsis.get_working_version())
            USING ERRCODE = 'TG200', HINT = 'SELECT name FROM tgsis.model lists the models';
    END IF;
    RETURN v_id;
END
$$;

COMMENT ON FUNCTION tgsis.model_id(text) IS 'id of the model called name in the session''s version; TG200 when there is none';
