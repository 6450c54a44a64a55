-- tgsis.older_snapshots_at_commit(what): queue tgsis.older_snapshots_check(what) for this transaction's COMMIT.
-- Called by tgsis.store_in_rows and tgsis.store_class_in_rows (their way
-- back makes a plain row table, which reads EMPTY to a snapshot older than
-- the switch's commit): besides the checks at their start and end, one at
-- the commit, so that a snapshot taken while the caller kept the transaction
-- open refuses the switch too (TG202 at COMMIT: the switch rolled back). A
-- row in the session's temporary table pg_temp.tgsis_older_snapshots (made
-- here, ON COMMIT DROP) fires the DEFERRABLE INITIALLY DEFERRED constraint
-- trigger tgsis.older_snapshots_commit_check; SET CONSTRAINTS ... IMMEDIATE
-- by the caller runs it at once instead (a check earlier than the commit:
-- the window grows back to what the end-of-function check leaves). Two
-- switches in one transaction queue two checks. Internal.
CREATE FUNCTION tgsis.older_snapshots_at_commit(p_what text)
RETURNS void
LANGUAGE plpgsql
VOLATILE
SET search_path = pg_catalog, pg_temp
AS $$
BEGIN
    IF to_regclass('pg_temp.tgsis_older_snapshots') IS NULL THEN
        CREATE TEMPORARY TABLE tgsis_older_snapshots (what text NOT NULL) ON COMMIT DROP;
        CREATE CONSTRAINT TRIGGER tgsis_older_snapshots AFTER INSERT ON pg_temp.tgsis_older_snapshots
            DEFERRABLE INITIALLY DEFERRED FOR EACH ROW EXECUTE FUNCTION tgsis.older_snapshots_commit_check();
    END IF;
    INSERT INTO pg_temp.tgsis_older_snapshots (what) VALUES (p_what);
END
$$;

REVOKE ALL ON FUNCTION tgsis.older_snapshots_at_commit(text) FROM PUBLIC;

COMMENT ON FUNCTION tgsis.older_snapshots_at_commit(text) IS
    'queue tgsis.older_snapshots_check(p_what) for this transaction''s commit (a deferred constraint trigger on a temporary table, ON COMMIT DROP): the way back into rows refused at COMMIT while another session holds a snapshot older than it';
