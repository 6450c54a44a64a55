-- The role tgsis_nobody: no rights of its own, and a member of no role.
-- tgsis's definer code runs as tgsis's owner; when it acts on a table
-- another role owns, it calls that table's runner (<table>_ver_run(),
-- SECURITY DEFINER, owned by the table's owner) from tgsis.storage_hop,
-- which runs as this role. Had the table's owner made its runner SECURITY
-- INVOKER, the runner's code would run as tgsis_nobody, which can do
-- nothing, instead of as tgsis's owner (docs/security.md). Like the group
-- roles, it belongs to the cluster and is created only when missing.
DO $do$
BEGIN
    IF NOT EXISTS (SELECT FROM pg_catalog.pg_roles WHERE rolname = 'tgsis_nobody') THEN
        IF NOT (SELECT rolsuper OR rolcreaterole FROM pg_catalog.pg_roles WHERE rolname = current_user) THEN
            RAISE EXCEPTION 'tgsis needs the role tgsis_nobody, and role % may not create roles', current_user
                USING ERRCODE = 'TG002',
                      DETAIL = 'Roles are shared by all databases of the cluster; creating them needs CREATEROLE.',
                      HINT = format('Ask a DBA to run once: CREATE ROLE tgsis_nobody NOLOGIN NOINHERIT; GRANT tgsis_nobody TO %I;',
                                    current_user);
        END IF;
        CREATE ROLE tgsis_nobody NOLOGIN NOINHERIT;
        COMMENT ON ROLE tgsis_nobody IS
            'tgsis: a role with no rights, as which tgsis calls the runners of tables other roles own (tgsis.storage_hop)';
    END IF;
END
$do$;
