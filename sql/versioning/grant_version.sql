-- tgsis.grant_version(version, privilege, role): give a role (or public) a right on a version; owner or tgsis_admin only.
CREATE FUNCTION tgsis.grant_version(p_version text, p_privilege text, p_role text)
RETURNS void
LANGUAGE plpgsql
VOLATILE
SECURITY DEFINER
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_id integer := tgsis.version_id(p_version);
BEGIN
    PERFORM tgsis.require_version_owner(v_id, 'grant rights on');
    PERFORM tgsis.check_role(p_role, true);
    INSERT INTO tgsis.version_privileges (versionid, grantee, privilege, granted_by)
    SELECT v_id, p_role, p, tgsis.calling_role() FROM unnest(tgsis.version_privilege_list(p_privilege)) AS p
        ON CONFLICT DO NOTHING;
END
$$;

COMMENT ON FUNCTION tgsis.grant_version(text, text, text) IS
    'grant a right on a version (write, create, merge, delete or all) to a role or public; only its owner or a tgsis_admin may';
