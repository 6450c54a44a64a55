-- tgsis.storage_run(table, dml, sql, $1..$5): run a statement over a versioned table's storage, as that storage's owner when tgsis's owner runs it.
-- p_sql names the storage itself (schema.<table>_ver, quoted); see
-- tgsis.storage_execute for p_dml, the parameters and the rows returned.
-- - Called by another role (an invoker function a reader or editor runs):
--   the statement runs with that role's rights, like any query of its own.
-- - Called in tgsis's definer code, as tgsis's owner, on storage tgsis's
--   owner owns (the feature tables): run directly, with the storage locked
--   first, so that it cannot be dropped and replaced by something else of
--   that name (its schema's owner could) between the owner check and the
--   statement.
-- - As tgsis's owner on storage another role owns: through its runner
--   <table>_ver_run() (tgsis.storage_runner_source), called from
--   tgsis.storage_hop as tgsis_nobody, with the call recorded in
--   tgsis.storage_calls for the runner to check: whatever the statement
--   runs of the table's own code (triggers, rules, defaults, checks, index
--   expressions, casts) runs as the table's owner, and a runner its owner
--   altered runs as tgsis_nobody at worst, never as tgsis's owner.
CREATE FUNCTION tgsis.storage_run(
    p_t   tgsis.versioned_tables,
    p_dml boolean,
    p_sql text,
    p_1   text[]    DEFAULT NULL,
    p_2   integer[] DEFAULT NULL,
    p_3   integer[] DEFAULT NULL,
    p_4   integer   DEFAULT NULL,
    p_5   bigint[]  DEFAULT NULL)
RETURNS SETOF text[]
LANGUAGE plpgsql
VOLATILE
AS $$
DECLARE
    v_storage text := tgsis.storage_table(p_t.schemaname, p_t.tablename);  -- <table>_ver, or tgsis.<table>_chunk
    v_tgsis   oid  := (SELECT n.nspowner FROM pg_catalog.pg_namespace n WHERE n.nspname = 'tgsis');
    v_owner   oid;
BEGIN
    IF current_user IS DISTINCT FROM pg_catalog.pg_get_userbyid(v_tgsis) THEN
        RETURN QUERY SELECT * FROM tgsis.storage_execute(p_dml, p_sql, p_1, p_2, p_3, p_4, p_5);
        RETURN;
    END IF;
    EXECUTE format('LOCK TABLE %s IN %s MODE', v_storage, CASE WHEN p_dml THEN 'ROW EXCLUSIVE' ELSE 'ACCESS SHARE' END);
    SELECT c.relowner INTO v_owner FROM pg_catalog.pg_class c WHERE c.oid = v_storage::regclass;
    IF v_owner = v_tgsis THEN
        RETURN QUERY SELECT * FROM tgsis.storage_execute(p_dml, p_sql, p_1, p_2, p_3, p_4, p_5);
        RETURN;
    END IF;
    IF pg_catalog.to_regprocedure(format('%I.%I(boolean, text, text[], integer[], integer[], integer, bigint[])',
                                         p_t.schemaname, p_t.tablename || '_ver_run')) IS NULL THEN
        RAISE EXCEPTION 'tgsis cannot act on %: its runner %.%() is missing', v_storage, quote_ident(p_t.schemaname),
                quote_ident(p_t.tablename || '_ver_run')
            USING ERRCODE = 'TG002',
                  DETAIL = 'tgsis acts on a table another role owns through that function, as the table''s owner.',
                  HINT = format('the table''s owner may run: SELECT tgsis.restore_storage_runner(%L)',
                                format('%I.%I', p_t.schemaname, p_t.tablename));
    END IF;
    INSERT INTO tgsis.storage_calls AS c (backend, runner)
    VALUES (pg_catalog.pg_backend_pid(), format('%I.%I', p_t.schemaname, p_t.tablename || '_ver_run'))
        ON CONFLICT (backend) DO UPDATE SET runner = excluded.runner;
    RETURN QUERY SELECT * FROM tgsis.storage_hop(p_t.schemaname, p_t.tablename || '_ver_run', p_dml, p_sql,
                                                 p_1, p_2, p_3, p_4, p_5);
    DELETE FROM tgsis.storage_calls c WHERE c.backend = pg_catalog.pg_backend_pid();
END
$$;

COMMENT ON FUNCTION tgsis.storage_run(tgsis.versioned_tables, boolean, text, text[], integer[], integer[], integer, bigint[]) IS
    'run a statement (p_dml: one row, its row count) or query (text[] rows) over a versioned table''s storage: with the caller''s rights, or, as tgsis''s owner on storage another role owns, through its runner <table>_ver_run() as that owner';
