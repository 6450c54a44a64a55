-- tgsis.revoke_version(version, privilege, role): take back a granted right; owner or tgsis_admin only.
-- Ownership and tgsis_admin membership are not grants and stay.
CREATE FUNCTION tgsis.revoke_version(p_version text, p_privilege text, p_role text)
RETURNS void
LANGUAGE plpgsql
VOLATILE
SECURITY DEFINER
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_id integer := tgsis.version_id(p_version);
BEGIN
    PERFORM tgsis.require_version_owner(v_id, 'revoke rights on');
    PERFORM tgsis.check_role(p_role, true);
    DELETE FROM tgsis.version_privileges
     WHERE versionid = v_id AND grantee = p_role AND privilege = ANY (tgsis.version_privilege_list(p_privilege));
END
$$;

COMMENT ON FUNCTION tgsis.revoke_version(text, text, text) IS
    'revoke a granted right on a version (write, create, merge, delete or all) from a role or public; only its owner or a tgsis_admin may';
