-- tgsis.has_version_privilege(version, privilege, role): whether a role holds a right on a version.
-- Superusers, members of tgsis_admin and of the version's owner hold them all;
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
BEGIN
    IF p_privilege IS NULL OR lower(p_privilege) NOT IN ('write', 'create', 'merge', 'delete') THEN
        RAISE EXCEPTION 'unknown version privilege %', coalesce(quote_literal(p_privilege), 'NULL')
            USING ERRCODE = 'TG100', HINT = 'version privileges: write, create, merge, delete';
    END IF;
    IF NOT EXISTS (SELECT FROM pg_roles WHERE rolname = v_role) THEN
        RAISE EXCEPTION 'role % does not exist', quote_literal(v_role) USING ERRCODE = 'TG200';
    END IF;
    SELECT * INTO v_version FROM tgsis.versions WHERE versionid = tgsis.version_id(p_version);
    RETURN tgsis.holds_version_privilege(v_version.versionid, lower(p_privilege), v_role);
END
$$;

COMMENT ON FUNCTION tgsis.has_version_privilege(text, text, name) IS
    'whether a role (default: the calling role) holds a right (write, create, merge, delete) on a version: as its owner, as a tgsis_admin, or by a grant';
