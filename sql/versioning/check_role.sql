-- tgsis.check_role(role, allow_public): TG200 unless the role exists (or, when allowed, is public).
CREATE FUNCTION tgsis.check_role(p_role text, p_allow_public boolean DEFAULT false)
RETURNS void
LANGUAGE plpgsql
STABLE
AS $$
BEGIN
    IF p_role IS NULL
       OR NOT ((p_allow_public AND p_role = 'public') OR EXISTS (SELECT FROM pg_catalog.pg_roles WHERE rolname = p_role)) THEN
        RAISE EXCEPTION 'role % does not exist', coalesce(quote_literal(p_role), 'NULL')
            USING ERRCODE = 'TG200',
                  HINT = CASE WHEN p_allow_public THEN 'name an existing role, or public for every role'
                              ELSE 'name an existing role' END;
    END IF;
END
$$;

COMMENT ON FUNCTION tgsis.check_role(text, boolean) IS
    'raise TG200 naming the role unless it exists (or p_allow_public and it is public)';
