-- tgsis.is_version_owner(versionid, role): whether a role owns a version in the sense of its rights.
-- The owner of the version or of any ancestor (whoever owns a version
-- manages the versions made below it), roles using their rights (members),
-- tgsis_admin members and superusers (pg_has_role is true for them).
CREATE FUNCTION tgsis.is_version_owner(p_versionid integer, p_role name)
RETURNS boolean
LANGUAGE sql
STABLE
AS $$
    WITH RECURSIVE line AS (
        SELECT versionid, parentid, owner FROM tgsis.versions WHERE versionid = p_versionid
        UNION ALL
        SELECT v.versionid, v.parentid, v.owner FROM tgsis.versions v JOIN line ON v.versionid = line.parentid
    )
    SELECT pg_catalog.pg_has_role(p_role, 'tgsis_admin', 'USAGE')
        OR EXISTS (SELECT FROM line
                    WHERE line.owner = p_role
                       OR (EXISTS (SELECT FROM pg_catalog.pg_roles WHERE rolname = line.owner)
                           AND pg_catalog.pg_has_role(p_role, line.owner, 'USAGE')))
$$;

COMMENT ON FUNCTION tgsis.is_version_owner(integer, name) IS
    'whether a role holds every right on a version: owner (or member of the owner) of it or of an ancestor, a tgsis_admin, or a superuser';
