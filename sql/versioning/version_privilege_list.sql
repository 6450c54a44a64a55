-- tgsis.version_privilege_list(privilege, role): the rights a grant or revoke names, checked; 'all' is all four.
CREATE FUNCTION tgsis.version_privilege_list(p_privilege text, p_role text)
RETURNS text[]
LANGUAGE plpgsql
STABLE
AS $$
BEGIN
    IF p_role IS NULL OR (p_role <> 'public' AND NOT EXISTS (SELECT FROM pg_catalog.pg_roles WHERE rolname = p_role)) THEN
        RAISE EXCEPTION 'role % does not exist', coalesce(quote_literal(p_role), 'NULL')
            USING ERRCODE = 'TG200', HINT = 'name an existing role, or public for every role';
    END IF;
    IF lower(p_privilege) = 'all' THEN
        RETURN ARRAY['write', 'create', 'merge', 'delete'];
    ELSIF p_privilege IS NULL OR lower(p_privilege) NOT IN ('write', 'create', 'merge', 'delete') THEN
        RAISE EXCEPTION 'unknown version privilege %', coalesce(quote_literal(p_privilege), 'NULL')
            USING ERRCODE = 'TG100', HINT = 'version privileges: write, create, merge, delete, or all';
    END IF;
    RETURN ARRAY[lower(p_privilege)];
END
$$;

COMMENT ON FUNCTION tgsis.version_privilege_list(text, text) IS
    'the version rights named by p_privilege (one of write, create, merge, delete, or all), after checking that p_role exists (or is public)';
