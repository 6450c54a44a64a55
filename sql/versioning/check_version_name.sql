-- tgsis.check_version_name(name, what): raise TG101 unless the name is a usable version or revision name.
CREATE FUNCTION tgsis.check_version_name(p_name text, p_what text DEFAULT 'version')
RETURNS text
LANGUAGE plpgsql
IMMUTABLE
PARALLEL SAFE
AS $$
BEGIN
    IF p_name IS NULL OR p_name !~ '^[[:alnum:]_][[:alnum:]_.+-]{0,62}$' THEN
        RAISE EXCEPTION '% name % is not allowed', p_what, coalesce(quote_literal(p_name), 'NULL')
            USING ERRCODE = 'TG101',
                  DETAIL = 'Names are 1 to 63 characters: letters, digits and _ . + -, not starting with . + or -. (@ is kept for VERSION@REVISION on the command line.)';
    END IF;
    RETURN p_name;
END
$$;

COMMENT ON FUNCTION tgsis.check_version_name(text, text) IS
    'returns the name when it is a valid version or revision name (1-63 letters, digits, _ . + -), else raises TG101';
