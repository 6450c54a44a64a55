-- tgsis.checked_operator(op): a comparison operator of the temporal questions ('<', '<=', '>', '>=', '=' or '<>'), or TG100 naming it.
CREATE FUNCTION tgsis.checked_operator(p_op text)
RETURNS text
LANGUAGE plpgsql
IMMUTABLE
PARALLEL SAFE
AS $$
BEGIN
    IF p_op IN ('<', '<=', '>', '>=', '=', '<>') THEN
        RETURN p_op;
    END IF;
    RAISE EXCEPTION 'comparison operator % is not one of <, <=, >, >=, =, <>', coalesce(quote_literal(p_op), 'NULL')
        USING ERRCODE = 'TG100',
              HINT = 'the condition is "value op v", e.g. op => ''>='' for values of at least v';
END
$$;

COMMENT ON FUNCTION tgsis.checked_operator(text) IS
    'a comparison operator of the temporal questions: <, <=, >, >=, = or <>; TG100 otherwise';
