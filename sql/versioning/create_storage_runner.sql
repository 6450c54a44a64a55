-- tgsis.create_storage_runner(schema, table): (re)create the runner <table>_ver_run() of a versioned table, owned by its storage's owner.
-- See tgsis.storage_runner_source for why it exists. Called by
-- enable_versioning, and by tgsis.restore_storage_runner when the runner
-- was dropped, altered or the storage changed owner. Runs with the
-- caller's rights: only a role that may act as the storage's owner can
-- give that owner a function.
CREATE FUNCTION tgsis.create_storage_runner(p_schema text, p_table text)
RETURNS void
LANGUAGE plpgsql
VOLATILE
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_owner name := (SELECT pg_get_userbyid(c.relowner) FROM pg_class c
                      WHERE c.oid = format('%I.%I', p_schema, p_table || '_ver')::regclass);
    v_sig   CONSTANT text := '(boolean, text, text[], integer[], integer[], integer, bigint[])';
BEGIN
    IF NOT pg_has_role(current_user, v_owner, 'USAGE') THEN
        RAISE EXCEPTION 'only the owner of %.% (%) may give it a runner', quote_ident(p_schema), quote_ident(p_table || '_ver'),
                v_owner
            USING ERRCODE = 'TG002';
    END IF;
    EXECUTE format('DROP FUNCTION IF EXISTS %I.%I%s', p_schema, p_table || '_ver_run', v_sig);
    EXECUTE tgsis.storage_runner_source(p_schema, p_table);
    EXECUTE format('ALTER FUNCTION %I.%I%s OWNER TO %I', p_schema, p_table || '_ver_run', v_sig, v_owner);
    EXECUTE format('REVOKE ALL ON FUNCTION %I.%I%s FROM PUBLIC', p_schema, p_table || '_ver_run', v_sig);
    EXECUTE format('GRANT EXECUTE ON FUNCTION %I.%I%s TO tgsis_nobody', p_schema, p_table || '_ver_run', v_sig);
    -- tgsis.storage_hop calls it by name, as tgsis_nobody
    IF NOT has_schema_privilege('tgsis_nobody', p_schema, 'USAGE') THEN
        BEGIN
            EXECUTE format('GRANT USAGE ON SCHEMA %I TO tgsis_nobody', p_schema);
        EXCEPTION WHEN insufficient_privilege THEN
            RAISE EXCEPTION 'tgsis_nobody needs USAGE on schema % to call the runner of %.%', quote_ident(p_schema),
                    quote_ident(p_schema), quote_ident(p_table)
                USING ERRCODE = 'TG002',
                      DETAIL = 'tgsis calls a versioned table''s runner as tgsis_nobody, a role with no rights.',
                      HINT = format('the owner of schema %I may run: GRANT USAGE ON SCHEMA %I TO tgsis_nobody', p_schema, p_schema);
        END;
    END IF;
    EXECUTE format('COMMENT ON FUNCTION %I.%I%s IS %L', p_schema, p_table || '_ver_run', v_sig,
                   format('tgsis versioning: runs tgsis''s statements on %I.%I as its owner (see tgsis.storage_runner_source); '
                          'only its owner may call it', p_schema, p_table || '_ver'));
END
$$;

COMMENT ON FUNCTION tgsis.create_storage_runner(text, text) IS
    '(re)create <schema>.<table>_ver_run(), the SECURITY DEFINER runner through which tgsis acts on a versioned table''s storage as its owner; the caller must be able to act as that owner';
