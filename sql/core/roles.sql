-- Group roles of tgsis, each one a member of the one before:
--   tgsis_reader  reads features, versions and history;
--   tgsis_editor  also writes features and works in versions;
--   tgsis_admin   also registers feature classes and merges into DEFAULT.
-- Roles belong to the cluster, not to a database: they are created only when
-- missing and outlive DROP EXTENSION. Without CREATEROLE the install fails
-- with TG002 and tells the DBA what to run, rather than half-installing.
DO $do$
DECLARE
    v_roles   CONSTANT text[] := ARRAY['tgsis_reader', 'tgsis_editor', 'tgsis_admin'];
    v_comment CONSTANT text[] := ARRAY[
        'tgsis group role: read features, versions and their history',
        'tgsis group role: tgsis_reader plus writing features and working in versions',
        'tgsis group role: tgsis_editor plus registering feature classes and merging into DEFAULT'];
    v_missing text[];
    v_i       int;
BEGIN
    SELECT coalesce(array_agg(r ORDER BY ord), '{}')
      INTO v_missing
      FROM unnest(v_roles) WITH ORDINALITY AS u(r, ord)
     WHERE NOT EXISTS (SELECT FROM pg_catalog.pg_roles WHERE rolname = u.r);

    IF cardinality(v_missing) > 0
       AND NOT (SELECT rolsuper OR rolcreaterole FROM pg_catalog.pg_roles WHERE rolname = current_user) THEN
        -- everything the DBA must run once, tgsis_nobody too (core/nobody_role.sql, versioning/storage_hop.sql)
        RAISE EXCEPTION 'tgsis needs the group roles %, and role % may not create roles',
                array_to_string(v_missing, ', '), current_user
            USING ERRCODE = 'TG002',
                  DETAIL = 'Roles are shared by all databases of the cluster; creating them needs CREATEROLE.',
                  -- (and tgsis_admin to the installer: tgsis's owner registers classes and versions features)
                  HINT = format('Ask a DBA to run once: %s GRANT tgsis_reader TO tgsis_editor; GRANT tgsis_editor TO tgsis_admin; GRANT tgsis_admin TO %I;%s',
                                (SELECT string_agg(format('CREATE ROLE %I NOLOGIN;', r), ' ') FROM unnest(v_missing) AS r),
                                current_user,
                                CASE WHEN NOT EXISTS (SELECT FROM pg_catalog.pg_roles WHERE rolname = 'tgsis_nobody')
                                     THEN format(' CREATE ROLE tgsis_nobody NOLOGIN NOINHERIT; GRANT tgsis_nobody TO %I;', current_user)
                                     WHEN NOT pg_catalog.pg_has_role(current_user, 'tgsis_nobody', 'MEMBER')
                                     THEN format(' GRANT tgsis_nobody TO %I;', current_user)
                                     ELSE '' END);
    END IF;

    FOR v_i IN 1 .. cardinality(v_roles) LOOP
        IF v_roles[v_i] = ANY (v_missing) THEN
            EXECUTE format('CREATE ROLE %I NOLOGIN', v_roles[v_i]);
            EXECUTE format('COMMENT ON ROLE %I IS %L', v_roles[v_i], v_comment[v_i]);
        END IF;
        -- editor is a reader, admin is an editor
        IF v_i > 1 AND NOT pg_catalog.pg_has_role(v_roles[v_i], v_roles[v_i - 1], 'MEMBER') THEN
            EXECUTE format('GRANT %I TO %I', v_roles[v_i - 1], v_roles[v_i]);
        END IF;
    END LOOP;
END
$do$;
