-- tgsis.goto_version(name, local): make a version the session's (or, with local, the transaction's) working version.
CREATE FUNCTION tgsis.goto_version(p_name text, p_local boolean DEFAULT false)
RETURNS text
LANGUAGE plpgsql
VOLATILE
AS $$
BEGIN
    PERFORM tgsis.version_id(p_name);
    PERFORM set_config('tgsis.version', p_name, coalesce(p_local, false));
    PERFORM set_config('tgsis.revision', '', coalesce(p_local, false));
    RETURN p_name;
END
$$;

COMMENT ON FUNCTION tgsis.goto_version(text, boolean) IS
    'work in a version from now on (the viewing revision is cleared); p_local => true: only until the transaction ends (for poolers in transaction mode)';
