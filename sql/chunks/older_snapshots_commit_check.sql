-- tgsis.older_snapshots_commit_check(): the deferred constraint trigger running tgsis.older_snapshots_check at COMMIT.
-- A storage switch back into rows checks for older snapshots at its start
-- and as its last statement (tgsis.older_snapshots_check); a snapshot taken
-- after the function returned and before its transaction commits (the
-- caller kept the transaction open) would still read the new row table
-- EMPTY. tgsis.older_snapshots_at_commit queues one more check for the
-- commit itself: a row in a temporary table (ON COMMIT DROP) whose
-- DEFERRABLE INITIALLY DEFERRED constraint trigger is this function, fired
-- before the commit is written (PostgreSQL fires deferred triggers first in
-- its commit). TG202 there rolls the whole switch back. The window left is
-- the commit's own writing (from this check to the commit record's flush):
-- docs/storage.md. NEW.what names the switch. SECURITY DEFINER (as tgsis's
-- owner, pinned search_path): a deferred trigger fires at COMMIT as the
-- session's role, outside the SECURITY DEFINER switch that queued it (a
-- tgsis_admin member's tgsis.store_class_in_rows), and the check is
-- internal. Internal.
CREATE FUNCTION tgsis.older_snapshots_commit_check()
RETURNS trigger
LANGUAGE plpgsql
VOLATILE
SECURITY DEFINER
SET search_path = pg_catalog, pg_temp
AS $$
BEGIN
    PERFORM tgsis.older_snapshots_check(NEW.what);
    RETURN NULL;
END
$$;

REVOKE ALL ON FUNCTION tgsis.older_snapshots_commit_check() FROM PUBLIC;

COMMENT ON FUNCTION tgsis.older_snapshots_commit_check() IS
    'deferred constraint trigger of tgsis.older_snapshots_at_commit''s temporary table: tgsis.older_snapshots_check(NEW.what) when the transaction commits (TG202 rolls the switch back)';
