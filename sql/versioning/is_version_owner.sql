-- tgsis.is_version_owner(versionid, role): whether a role owns a version in the sense of its rights.
-- The owner of the version or of any ancestor (whoever owns a version
-- manages the versions made below it), roles using their rights (members),
-- tgsis_admin members and superusers (pg_has_role is true for them).
-- PL/pgSQL, not SQL: the write triggers ask once per row, and PL/pgSQL keeps
-- its plans for the session where a SQL function would be planned per call.
CREATE FUNCTION tgsis.is_version_owner(p_versionid integer, p_role name)
RETURNS boolean
LANGUAGE plpgsql
STABLE
AS $$
DECLARE
    v_owner  name;
    v_parent integer := p_versionid;
BEGIN
    IF pg_catalog.pg_has_role(p_role, 'tgsis_admin', 'USAGE') THEN
        RETURN true;
    END IF;
    WHILE v_parent IS NOT NULL LOOP
        SELECT owner, parentid INTO v_owner, v_parent FROM tgsis.versions WHERE versionid = v_parent;
        IF v_owner = p_role
           OR (EXISTS (SELECT FROM pg_catalog.pg_roles WHERE rolname = v_owner)
               AND pg_catalog.pg_has_role(p_role, v_owner, 'USAGE')) THEN
            RETURN true;
        END IF;
    END LOOP;
    RETURN false;
END
$$;

COMMENT ON FUNCTION tgsis.is_version_owner(integer, name) IS
    'whether a role holds every right on a version: owner (or member of the owner) of it or of an ancestor, a tgsis_admin, or a superuser';
