-- tgsis.calling_role(): the role a session acts as, also inside SECURITY DEFINER functions.
-- There current_user is the function's owner; the session's role is the one
-- SET ROLE chose (the role setting), or else the role that logged in. Both
-- can only be roles the login may act as, so the answer cannot be forged.
CREATE FUNCTION tgsis.calling_role()
RETURNS name
LANGUAGE sql
STABLE
PARALLEL SAFE
AS $$
    SELECT CASE WHEN pg_catalog.current_setting('role') = 'none' THEN session_user
                ELSE pg_catalog.current_setting('role')::name END
$$;

COMMENT ON FUNCTION tgsis.calling_role() IS
    'the role the session acts as (SET ROLE''s role, else the login role), also inside SECURITY DEFINER functions: whose version rights are checked';
