-- tgsis.require_version_privilege(versionid, privilege, doing): TG002 unless the calling role holds the right.
-- p_doing says what was refused ("merge into", "delete", ...) for the message.
-- Called by the SECURITY DEFINER version functions (and, through
-- write_revision, once per row by the write triggers): no SET clause of its
-- own, which would cost a configuration change per call.
CREATE FUNCTION tgsis.require_version_privilege(p_versionid integer, p_privilege text, p_doing text)
RETURNS void
LANGUAGE plpgsql
STABLE
AS $$
DECLARE
    v_version tgsis.versions;
    v_role    name := tgsis.calling_role();
BEGIN
    IF tgsis.holds_version_privilege(p_versionid, p_privilege, v_role) THEN
        RETURN;
    END IF;
    SELECT * INTO v_version FROM tgsis.versions WHERE versionid = p_versionid;
    RAISE EXCEPTION 'role % may not % version %', quote_ident(v_role), p_doing, quote_literal(v_version.name)
        USING ERRCODE = 'TG002',
              DETAIL = format('That needs the %s right on %s, held by its owner %s, by tgsis_admin and by the roles it was granted to.',
                              lower(p_privilege), v_version.name, quote_ident(v_version.owner)),
              HINT = format('the owner or a tgsis_admin can run SELECT tgsis.grant_version(%L, %L, %L)',
                            v_version.name, lower(p_privilege), v_role);
END
$$;

COMMENT ON FUNCTION tgsis.require_version_privilege(integer, text, text) IS
    'raise TG002 (naming the role, the action and the version) unless the calling role holds the right on the version';
