-- tgsis.holds_version_privilege(versionid, privilege, role): the rule behind has_version_privilege, for callers that checked their arguments.
-- Ownership (tgsis.is_version_owner) or a grant to public or to a role
-- whose rights p_role uses.
CREATE FUNCTION tgsis.holds_version_privilege(p_versionid integer, p_privilege text, p_role name)
RETURNS boolean
LANGUAGE plpgsql
STABLE
AS $$
BEGIN
    RETURN EXISTS (SELECT FROM tgsis.version_privileges p LEFT JOIN pg_catalog.pg_roles r ON r.rolname = p.grantee
                    WHERE p.versionid = p_versionid AND p.privilege = p_privilege
                      AND (p.grantee = 'public' OR (r.oid IS NOT NULL AND pg_catalog.pg_has_role(p_role, r.oid, 'USAGE'))))
        OR tgsis.is_version_owner(p_versionid, p_role);
END
$$;

COMMENT ON FUNCTION tgsis.holds_version_privilege(integer, text, name) IS
    'whether p_role holds p_privilege on a version (owner, ancestor owner, tgsis_admin, or a grant); arguments unchecked: use tgsis.has_version_privilege';
