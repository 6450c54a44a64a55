-- tgsis.require_version_owner(versionid, doing): TG002 unless the calling role owns the version or is a tgsis_admin.
-- For what only an owner may do: grant and revoke rights, change the owner,
-- set the validity period.
CREATE FUNCTION tgsis.require_version_owner(p_versionid integer, p_doing text)
RETURNS void
LANGUAGE plpgsql
STABLE
AS $$
DECLARE
    v_version tgsis.versions;
    v_role    name := tgsis.calling_role();
BEGIN
    SELECT * INTO v_version FROM tgsis.versions WHERE versionid = p_versionid;
    IF NOT tgsis.is_version_owner(p_versionid, v_role) THEN
        RAISE EXCEPTION 'role % may not % version %', quote_ident(v_role), p_doing, quote_literal(v_version.name)
            USING ERRCODE = 'TG002',
                  DETAIL = format('Only its owner %s, the owners of its ancestors and tgsis_admin may.', quote_ident(v_version.owner));
    END IF;
END
$$;

COMMENT ON FUNCTION tgsis.require_version_owner(integer, text) IS
    'raise TG002 unless the calling role is (a member of) the version''s owner or a tgsis_admin';
