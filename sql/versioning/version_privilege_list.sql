-- tgsis.version_privilege_list(privilege): the rights a privilege name stands for, checked; 'all' is all four.
CREATE FUNCTION tgsis.version_privilege_list(p_privilege text)
RETURNS text[]
LANGUAGE plpgsql
IMMUTABLE
AS $$
BEGIN
    IF lower(p_privilege) = 'all' THEN
        RETURN ARRAY['write', 'create', 'merge', 'delete'];
    ELSIF p_privilege IS NULL OR lower(p_privilege) NOT IN ('write', 'create', 'merge', 'delete') THEN
        RAISE EXCEPTION 'unknown version privilege %', coalesce(quote_literal(p_privilege), 'NULL')
            USING ERRCODE = 'TG100', HINT = 'version privileges: write, create, merge, delete, or all';
    END IF;
    RETURN ARRAY[lower(p_privilege)];
END
$$;

COMMENT ON FUNCTION tgsis.version_privilege_list(text) IS
    'the version rights named by p_privilege (write, create, merge, delete, or all for the four); TG100 for any other name';
