-- tgsis.is_version_owner(versionid, role): whether a role owns a version in the sense of its rights.
-- The owner itself, roles using its rights (members), tgsis_admin members and
-- superusers (pg_has_role is true for them).
CREATE FUNCTION tgsis.is_version_owner(p_versionid integer, p_role name)
RETURNS boolean
LANGUAGE sql
STABLE
AS $$
    SELECT p_role = v.owner
        OR pg_catalog.pg_has_role(p_role, 'tgsis_admin', 'USAGE')
        OR (EXISTS (SELECT FROM pg_catalog.pg_roles WHERE rolname = v.owner)
            AND pg_catalog.pg_has_role(p_role, v.owner, 'USAGE'))
      FROM tgsis.versions v
     WHERE v.versionid = p_versionid
$$;

COMMENT ON FUNCTION tgsis.is_version_owner(integer, name) IS
    'whether a role holds every right on a version: its owner (or a member of it), a tgsis_admin, or a superuser';
