-- tgsis.storage_runner_source(schema, table): CREATE FUNCTION of a versioned table's runner <table>_ver_run().
-- tgsis's definer functions (merge, refresh, delete_version, compress,
-- conflicts, set-based deletes) run as tgsis's owner. What a statement on a
-- table runs besides the statement itself (its triggers and rules, the
-- expressions of its defaults, checks and indexes, casts of its row type)
-- is its owner's code: run as tgsis's owner, an application's table could
-- make any role its owner chose a superuser. So on a table another role
-- owns, they run their statements through this function, SECURITY DEFINER
-- and owned by the table's owner (enable_versioning sets it so): the
-- table's code then runs as the table's owner, who could run it anyway.
-- Besides its owner (and superusers) only tgsis_nobody may call it, as
-- which tgsis.storage_hop calls it, and it refuses to run unless tgsis is
-- calling it right now (tgsis.check_storage_call).
CREATE FUNCTION tgsis.storage_runner_source(p_schema text, p_table text)
RETURNS text
LANGUAGE sql
IMMUTABLE
PARALLEL SAFE
AS $$
    SELECT format(
        'CREATE FUNCTION %I.%I(p_dml boolean, p_sql text, p_1 text[], p_2 integer[], p_3 integer[], p_4 integer, p_5 bigint[]) '
        'RETURNS SETOF text[] LANGUAGE sql VOLATILE SECURITY DEFINER SET search_path = pg_catalog, pg_temp '
        'AS %L',
        p_schema, p_table || '_ver_run',
        format('SELECT tgsis.check_storage_call(%L); '
               'SELECT * FROM tgsis.storage_execute(p_dml, p_sql, p_1, p_2, p_3, p_4, p_5)',
               format('%I.%I', p_schema, p_table || '_ver_run')))
$$;

COMMENT ON FUNCTION tgsis.storage_runner_source(text, text) IS
    'CREATE FUNCTION statement of <schema>.<table>_ver_run(dml, sql, $1..$5), the SECURITY DEFINER runner through which tgsis''s definer code acts on storage another role owns (as that owner)';
