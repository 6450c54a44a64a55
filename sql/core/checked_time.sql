-- tgsis.checked_time(t): t itself, or TG100 when it is NaN (no instant compares with it).
CREATE FUNCTION tgsis.checked_time(p_t double precision)
RETURNS double precision
LANGUAGE plpgsql
IMMUTABLE
PARALLEL SAFE
AS $$
BEGIN
    IF p_t = 'NaN' THEN
        RAISE EXCEPTION 'model time NaN is not a time'
            USING ERRCODE = 'TG100', HINT = 'give a number; -Infinity and Infinity mean before and after every instant';
    END IF;
    RETURN p_t;
END
$$;

COMMENT ON FUNCTION tgsis.checked_time(double precision) IS 'the model time given, or TG100 if it is NaN';
