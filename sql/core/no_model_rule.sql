-- tgsis.no_model_rule(timemodel, function, known): refuse a geometry or class whose data model a function has no rule for.
-- Functions that answer differently per data model (tgsis.exists_at,
-- property_at, vertices_at, ...) list the time models they have a rule
-- for (p_known); anything else comes here instead of falling into another model's rule
-- (an unknown model once answered as model 3: exists_at false, features_at
-- empty, no error). The message names the model from the registry
-- (tgsis.data_models) when it is registered, and says so when it is not.
-- Returns boolean so that SQL functions can call it in a CASE or WHERE; it
-- never returns.
CREATE FUNCTION tgsis.no_model_rule(p_timemodel text, p_function text, p_known text[])
RETURNS boolean
LANGUAGE plpgsql
STABLE
PARALLEL SAFE
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_model tgsis.data_models;
BEGIN
    SELECT * INTO v_model FROM tgsis.data_models m WHERE m.timemodel = p_timemodel;
    IF NOT FOUND THEN
        RAISE EXCEPTION 'time model % is no registered data model', coalesce(quote_literal(left(p_timemodel, 100)), 'NULL')
            USING ERRCODE = 'TG203',
                  DETAIL = format('%s answers for the time models %s only, and tgsis.data_models has no row for this one.',
                                  p_function, array_to_string(p_known, ', ')),
                  HINT = 'SELECT model, name, timemodel FROM tgsis.data_models lists the registered models';
    END IF;
    RAISE EXCEPTION '% has no rule for data model % (%, time model %)', p_function, v_model.model, v_model.name,
            v_model.timemodel
        USING ERRCODE = 'TG203',
              DETAIL = format('%s answers for the time models %s only; it does not answer for another model as if it were one of them.',
                              p_function, array_to_string(p_known, ', ')),
              HINT = 'the model''s own functions answer for its geometries (docs/data-models.md)';
END
$$;

COMMENT ON FUNCTION tgsis.no_model_rule(text, text, text[]) IS
    'raise TG203 naming a data model (from tgsis.data_models, or as unregistered) that a per-model function has no rule for; never returns';
