-- tgsis.require_version_privilege(versionid, privilege, doing): TG002 unless the calling role holds the right.
-- p_doing says what was refused ("merge into", "delete", ...) for the message.
CREATE FUNCTION tgsis.require_version_privilege(p_versionid integer, p_privilege text, p_doing text)
RETURNS void
LANGUAGE plpgsql
STABLE
SECURITY DEFINER
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_version tgsis.versions;
    v_role    name := tgsis.calling_role();
BEGIN
    SELECT * INTO v_version FROM tgsis.versions WHERE versionid = p_versionid;
    IF NOT tgsis.has_version_privilege(v_version.name, p_privilege, v_role) THEN
        RAISE EXCEPTION 'role % may not % version %', quote_ident(v_role), p_doing, quote_literal(v_version.name)
            USING ERRCODE = 'TG002',
                  DETAIL = format('That needs the %s right on %s, held by its owner %s, by tgsis_admin and by the roles it was granted to.',
                                  lower(p_privilege), v_version.name, quote_ident(v_version.owner)),
                  HINT = format('the owner or a tgsis_admin can run SELECT tgsis.grant_version(%L, %L, %L)',
                                v_version.name, lower(p_privilege), v_role);
    END IF;
END
$$;

COMMENT ON FUNCTION tgsis.require_version_privilege(integer, text, text) IS
    'raise TG002 (naming the role, the action and the version) unless the calling role holds the right on the version';
