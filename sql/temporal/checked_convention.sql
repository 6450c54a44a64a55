-- tgsis.checked_convention(convention): 'left' or 'right' (lower-cased), or TG100 naming the bad value.
CREATE FUNCTION tgsis.checked_convention(p_convention text)
RETURNS text
LANGUAGE plpgsql
IMMUTABLE
PARALLEL SAFE
AS $$
BEGIN
    IF lower(p_convention) IN ('left', 'right') THEN
        RETURN lower(p_convention);
    END IF;
    RAISE EXCEPTION 'step convention % must be left or right', coalesce(quote_literal(p_convention), 'NULL')
        USING ERRCODE = 'TG100',
              DETAIL = 'left-closed: G(t) = G_i for t_i <= t < t_i+1; right-closed: G(t) = G_i for t_i-1 < t <= t_i.';
END
$$;

COMMENT ON FUNCTION tgsis.checked_convention(text) IS
    'the step convention of model-2 queries, ''left'' (left-closed) or ''right'' (right-closed); TG100 otherwise';
