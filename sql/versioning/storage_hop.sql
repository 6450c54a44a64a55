-- tgsis.storage_hop(schema, runner, dml, sql, $1..$5): call a table's runner as tgsis_nobody.
-- SECURITY DEFINER, owned by tgsis_nobody (see sql/core/nobody_role.sql):
-- a runner is SECURITY DEFINER, so it runs as its table's owner whoever
-- calls it; should its owner have made it SECURITY INVOKER, it runs as
-- tgsis_nobody, which may do nothing, rather than as tgsis's owner. Only
-- tgsis's owner calls it (tgsis.storage_run).
CREATE FUNCTION tgsis.storage_hop(
    p_schema text,
    p_runner text,
    p_dml    boolean,
    p_sql    text,
    p_1      text[],
    p_2      integer[],
    p_3      integer[],
    p_4      integer,
    p_5      bigint[])
RETURNS SETOF text[]
LANGUAGE plpgsql
VOLATILE
SECURITY DEFINER
SET search_path = pg_catalog, pg_temp
AS $$
BEGIN
    RETURN QUERY EXECUTE format('SELECT * FROM %I.%I($1, $2, $3, $4, $5, $6, $7)', p_schema, p_runner)
        USING p_dml, p_sql, p_1, p_2, p_3, p_4, p_5;
END
$$;

COMMENT ON FUNCTION tgsis.storage_hop(text, text, boolean, text, text[], integer[], integer[], integer, bigint[]) IS
    'call the runner p_schema.p_runner() of a versioned table as tgsis_nobody (no rights), so that a runner made SECURITY INVOKER cannot run as tgsis''s owner; for tgsis.storage_run only';

REVOKE ALL ON FUNCTION tgsis.storage_hop(text, text, boolean, text, text[], integer[], integer[], integer, bigint[]) FROM PUBLIC;
GRANT EXECUTE ON FUNCTION tgsis.storage_hop(text, text, boolean, text, text[], integer[], integer[], integer, bigint[])
    TO CURRENT_USER;
DO $do$
DECLARE
    v_may_set boolean := pg_catalog.pg_has_role(current_user, 'tgsis_nobody', 'MEMBER');
BEGIN
    -- giving a function to a role needs the right to SET ROLE to it (or being a superuser). From
    -- PostgreSQL 16 a role that created tgsis_nobody (CREATEROLE) is a member with ADMIN OPTION but
    -- without SET: MEMBER is true and the ALTER below would fail (PostgreSQL 15 knows no 'SET' here).
    IF v_may_set AND current_setting('server_version_num')::integer >= 160000 THEN
        v_may_set := pg_catalog.pg_has_role(current_user, 'tgsis_nobody', 'SET');
    END IF;
    IF NOT v_may_set THEN
        BEGIN
            GRANT tgsis_nobody TO CURRENT_USER;
        EXCEPTION WHEN insufficient_privilege THEN
            RAISE EXCEPTION 'tgsis needs its owner % to be a member of tgsis_nobody', current_user
                USING ERRCODE = 'TG002',
                      HINT = format('Ask a DBA to run once: GRANT tgsis_nobody TO %I;', current_user);
        END;
    END IF;
END
$do$;
-- (and the new owner's CREATE on the schema, which it needs no longer afterwards)
GRANT CREATE ON SCHEMA tgsis TO tgsis_nobody;
ALTER FUNCTION tgsis.storage_hop(text, text, boolean, text, text[], integer[], integer[], integer, bigint[]) OWNER TO tgsis_nobody;
REVOKE CREATE ON SCHEMA tgsis FROM tgsis_nobody;
