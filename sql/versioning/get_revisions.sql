-- tgsis.get_revisions(viewing): the session's viewing revision set (true) or working revision set (false).
-- Versioned views call it once per query (as a scalar subquery), so it is
-- one indexed lookup. SECURITY DEFINER: roles that may read a versioned view
-- need not read the version tables themselves. PARALLEL SAFE (it only reads
-- tables and settings, which parallel workers share): a view query may then
-- run in parallel workers, as a download's tables side by side do
-- (tgsis.db._transfer.columns_out_all).
CREATE FUNCTION tgsis.get_revisions(p_viewing boolean DEFAULT true)
RETURNS integer[]
LANGUAGE plpgsql
STABLE
PARALLEL SAFE
SECURITY DEFINER
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_name     text := tgsis.get_working_version();
    v_working  integer;
    v_set      integer[];
    v_viewing  integer;
BEGIN
    SELECT workingrevision, workingset INTO v_working, v_set FROM tgsis.versions WHERE name = v_name;
    IF NOT FOUND THEN
        RAISE EXCEPTION 'version % does not exist', quote_literal(v_name)
            USING ERRCODE = 'TG200',
                  DETAIL = 'The session''s working version (setting tgsis.version) names no version.',
                  HINT = 'SELECT tgsis.goto_version(''DEFAULT''); SELECT name FROM tgsis.versions lists the versions';
    END IF;
    IF NOT coalesce(p_viewing, true) THEN
        RETURN v_set;
    END IF;
    v_viewing := tgsis.get_viewing_revision();
    IF v_viewing IS NULL OR v_viewing = v_working THEN
        RETURN v_set;
    END IF;
    RETURN tgsis.revision_set((SELECT versionid FROM tgsis.versions WHERE name = v_name), v_viewing);
END
$$;

COMMENT ON FUNCTION tgsis.get_revisions(boolean) IS
    'the session''s viewing revision set (true, what queries see) or working revision set (false, what changes see), ascending';
