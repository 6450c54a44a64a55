-- tgsis.create_model(name, objects, description): a new model, a named set of objects, in the session's version; returns its id.
-- A model's name is unique in each version (two sessions creating one name
-- take turns on a transaction lock of the name, the second is refused).
-- Its rows are written through the tables' names: with versioning on, in
-- the session's version (the model and each object's membership are
-- versioned rows); one statement each, one transaction.
CREATE FUNCTION tgsis.create_model(p_name text, p_objects bigint[] DEFAULT '{}', p_description text DEFAULT NULL)
RETURNS bigint
LANGUAGE plpgsql
VOLATILE
SET search_path FROM CURRENT
AS $$
DECLARE
    v_objects bigint[];
    v_id      bigint;
BEGIN
    PERFORM tgsis.require_storage();  -- a bare CREATE EXTENSION: say what to run (geometry/require_storage.sql)
    PERFORM tgsis.plain_write_check('tgsis', 'model');
    IF p_name IS NULL OR btrim(p_name) = '' THEN
        RAISE EXCEPTION 'a model needs a name, got %', coalesce(quote_literal(p_name), 'NULL')
            USING ERRCODE = 'TG101', HINT = 'p_name => ''resource model 2024''';
    END IF;
    v_objects := tgsis.checked_objects(p_objects);
    PERFORM pg_advisory_xact_lock(hashtextextended('tgsis.model ' || p_name, 0));
    IF EXISTS (SELECT FROM tgsis.model m WHERE m.name = p_name) THEN
        RAISE EXCEPTION 'model % exists already in version %', quote_literal(p_name), quote_literal(tgsis.get_working_version())
            USING ERRCODE = 'TG201', HINT = 'choose another name, or add objects to it (tgsis.add_to_model)';
    END IF;
    INSERT INTO tgsis.model (name, description) VALUES (p_name, p_description) RETURNING modelid INTO v_id;
    INSERT INTO tgsis.model_object (geoid, modelid) SELECT o, v_id FROM unnest(v_objects) o;
    RETURN v_id;
END
$$;

COMMENT ON FUNCTION tgsis.create_model(text, bigint[], text) IS
    'create a model (a named set of objects, unique by name in the session''s version) with these stored objects; returns its id';
