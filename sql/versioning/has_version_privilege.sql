-- tgsis.has_version_privilege(version, privilege, role): whether a role holds a right on a version.
-- Superusers, members of tgsis_admin and owners of the version or of an
-- ancestor hold them all;
-- otherwise a grant in tgsis.version_privileges to public or to a role whose
-- rights the role uses (pg_has_role USAGE, as for table privileges).
CREATE FUNCTION tgsis.has_version_privilege(p_version text, p_privilege text, p_role name DEFAULT NULL)
RETURNS boolean
LANGUAGE plpgsql
STABLE
SECURITY DEFINER
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_role    name := coalesce(p_role, tgsis.calling_role());
    v_version tgsis.versions;
    v_wanted  text[] := tgsis.version_privilege_list(p_privilege);
BEGIN
    PERFORM tgsis.check_role(v_role);
    SELECT * INTO v_version FROM tgsis.versions WHERE versionid = tgsis.version_id(p_version);
    RETURN (SELECT bool_and(tgsis.holds_version_privilege(v_version.versionid, p, v_role)) FROM unnest(v_wanted) AS p);
END
$$;

COMMENT ON FUNCTION tgsis.has_version_privilege(text, text, name) IS
    'whether a role (default: the calling role) holds a right (write, create, merge, delete; all: the four) on a version: as its owner, as a tgsis_admin, or by a grant';
