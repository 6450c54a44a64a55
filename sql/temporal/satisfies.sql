-- tgsis.satisfies(x, op, v): whether x op v holds; NULL (unknown) when x is NULL or NaN. op must come from tgsis.checked_operator.
CREATE FUNCTION tgsis.satisfies(p_x double precision, p_op text, p_v double precision)
RETURNS boolean
LANGUAGE sql
IMMUTABLE
PARALLEL SAFE
AS $$
    SELECT CASE WHEN p_x = 'NaN' THEN NULL
                WHEN p_op = '<' THEN p_x < p_v
                WHEN p_op = '<=' THEN p_x <= p_v
                WHEN p_op = '>' THEN p_x > p_v
                WHEN p_op = '>=' THEN p_x >= p_v
                WHEN p_op = '=' THEN p_x = p_v
                WHEN p_op = '<>' THEN p_x <> p_v
           END
$$;

COMMENT ON FUNCTION tgsis.satisfies(double precision, text, double precision) IS
    'x op v for op in <, <=, >, >=, =, <>; NULL (condition unknown) when x is NULL or NaN';
