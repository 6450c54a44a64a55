-- tgsis.check_storage_call(runner): a runner's first step: refuse unless tgsis is calling it now in this backend.
-- See tgsis.storage_calls. SECURITY DEFINER: the runner runs as its table's
-- owner, who may not read tgsis.storage_calls.
CREATE FUNCTION tgsis.check_storage_call(p_runner text)
RETURNS void
LANGUAGE plpgsql
STABLE
SECURITY DEFINER
SET search_path = pg_catalog, pg_temp
AS $$
BEGIN
    IF NOT EXISTS (SELECT FROM tgsis.storage_calls c WHERE c.backend = pg_backend_pid() AND c.runner = p_runner) THEN
        RAISE EXCEPTION 'only tgsis may call %()', p_runner
            USING ERRCODE = 'TG002',
                  DETAIL = 'A versioned table''s runner acts on its storage for tgsis''s own functions (merges, deletes of versions).';
    END IF;
END
$$;

COMMENT ON FUNCTION tgsis.check_storage_call(text) IS
    'raise TG002 unless tgsis.storage_run is calling the runner p_runner (quoted schema.name) right now in this backend; the first statement of every <table>_ver_run()';
