-- tgsis.merge_number_text(x): a number for a message as Python's format(x, '.6g') writes it.
-- So that the NOTICEs of the SQL merge by region say a discard's largest
-- displacement in the very words of the Python client (tgsis.db.merging):
-- six significant digits, trailing zeros dropped, scientific notation (two
-- exponent digits at least) below 1e-4 and from 1e6 on.
CREATE FUNCTION tgsis.merge_number_text(p_x double precision)
RETURNS text
LANGUAGE plpgsql
IMMUTABLE
PARALLEL SAFE
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_e integer;
    v_r numeric;
BEGIN
    IF p_x IS NULL THEN
        RETURN NULL;
    ELSIF p_x = 'NaN'::float8 THEN
        RETURN 'nan';
    ELSIF p_x = 'Infinity'::float8 THEN
        RETURN 'inf';
    ELSIF p_x = '-Infinity'::float8 THEN
        RETURN '-inf';
    ELSIF p_x = 0 THEN
        RETURN CASE WHEN float8send(p_x) = float8send('-0'::float8) THEN '-0' ELSE '0' END;
    END IF;
    v_e := floor(log(abs(p_x::numeric)));
    v_r := round(p_x::numeric, 5 - v_e);  -- six significant digits, which may carry into the next power of ten
    v_e := floor(log(abs(v_r)));
    IF v_e >= -4 AND v_e < 6 THEN
        RETURN trim_scale(round(v_r, greatest(5 - v_e, 0)))::text;
    END IF;
    RETURN format('%se%s%s', trim_scale(round(v_r / power(10::numeric, v_e), 5)),
                  CASE WHEN v_e < 0 THEN '-' ELSE '+' END, lpad(abs(v_e)::text, 2, '0'));
END
$$;

COMMENT ON FUNCTION tgsis.merge_number_text(double precision) IS
    'a number for a message as Python''s format(x, ''.6g'') writes it (six significant digits), for the NOTICEs of the SQL merge by region';

-- internal to the merges: reached only through the SECURITY DEFINER merge, refresh, find_conflicts and
-- resolve functions, as their owner; not executable by PUBLIC (tests/test_function_grants.py)
REVOKE ALL ON FUNCTION tgsis.merge_number_text(double precision) FROM PUBLIC;
