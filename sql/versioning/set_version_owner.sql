-- tgsis.set_version_owner(version, role): hand a version to another role; owner or tgsis_admin only.
CREATE FUNCTION tgsis.set_version_owner(p_version text, p_role text)
RETURNS void
LANGUAGE plpgsql
VOLATILE
SECURITY DEFINER
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_id integer := tgsis.version_id(p_version);
BEGIN
    PERFORM tgsis.require_version_owner(v_id, 'change the owner of');
    PERFORM tgsis.check_role(p_role);
    UPDATE tgsis.versions SET owner = p_role WHERE versionid = v_id;
END
$$;

COMMENT ON FUNCTION tgsis.set_version_owner(text, text) IS
    'make a role the owner of a version (it then holds every right on it); only the owner or a tgsis_admin may';
