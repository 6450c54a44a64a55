-- tgsis.older_snapshots_check(what): TG202 naming the sessions whose snapshot predates this transaction, else nothing.
-- The way back into rows (tgsis.store_in_rows, tgsis.store_class_in_rows)
-- makes a new PLAIN row table under the face's name and fills it in its own
-- transaction. A plain table cannot refuse a snapshot older than it (no view,
-- no InitPlan, no trigger runs on a SELECT; row-level security is bypassed by
-- superusers and the owner): a REPEATABLE READ or SERIALIZABLE snapshot taken
-- before the switch committed finds the new table by name (catalog lookups
-- read the latest catalog) and reads its rows with that snapshot, which does
-- not see the switch's transaction: EMPTY, silently (PostgreSQL's caveat for
-- a table made after a snapshot). So the switch refuses to run while such a
-- snapshot exists, called at its start (nothing done yet) and as its last
-- statement: every session of this database (or a physical walsender: a hot
-- standby's feedback) whose backend_xmin is not after this transaction's xid
-- holds a snapshot that may not see this transaction's commit; autovacuum is
-- left out (it reads no user's result), and so are this session's own
-- parallel workers (a query of the switch's verification can leave them
-- listed, with this transaction's snapshot, for a moment after it ends:
-- the whole suite on a loaded machine met it). A READ COMMITTED session in the middle
-- of a statement counts too (its xmin is there only while a statement runs:
-- retry). pg_stat_activity is read afresh (pg_stat_clear_snapshot: the
-- backends' status is otherwise cached for the transaction).
-- The window left (docs/storage.md, "Snapshots older than a change of
-- storage"): a snapshot taken after the last check and before the commit
-- (the switch's transaction kept open after the function returned, or the
-- commit itself) is not seen. backend_xmin is visible to every role (it is
-- among pg_stat_activity's columns for all callers). Internal.
CREATE FUNCTION tgsis.older_snapshots_check(p_what text)
RETURNS void
LANGUAGE plpgsql
VOLATILE
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_xid      xid := xid(pg_current_xact_id());  -- assigns this transaction's xid if it had none
    v_sessions text;
BEGIN
    PERFORM pg_stat_clear_snapshot();
    SELECT string_agg(format('pid %s (%s%s, since %s)', a.pid, coalesce(a.usename::text, a.backend_type),
                             CASE WHEN a.datid IS NULL THEN ', ' || a.backend_type ELSE '' END,
                             coalesce(a.xact_start, a.backend_start)), ', ' ORDER BY a.pid)
      INTO v_sessions
      FROM pg_stat_activity a
     WHERE a.pid <> pg_backend_pid()
       AND a.leader_pid IS DISTINCT FROM pg_backend_pid()  -- this session's own parallel workers, still exiting
       AND a.backend_xmin IS NOT NULL
       AND age(a.backend_xmin) >= age(v_xid)  -- backend_xmin <= this xid: that snapshot may not see this commit
       AND (a.datid = (SELECT d.oid FROM pg_database d WHERE d.datname = current_database())
            OR (a.datid IS NULL AND a.backend_type = 'walsender'))
       AND a.backend_type NOT IN ('autovacuum worker', 'autovacuum launcher');
    IF v_sessions IS NOT NULL THEN
        RAISE EXCEPTION '% is refused while other sessions hold an older snapshot', p_what
            USING ERRCODE = 'TG202',
                  DETAIL = format('These sessions hold a snapshot taken before this transaction could commit: %s. '
                                  'The row table it makes would read EMPTY to them (a table made after a snapshot).',
                                  v_sessions),
                  HINT = 'retry when those transactions have ended (pg_stat_activity lists them; pg_terminate_backend ends one), and run the switch in a transaction of its own';
    END IF;
END
$$;

REVOKE ALL ON FUNCTION tgsis.older_snapshots_check(text) FROM PUBLIC;

COMMENT ON FUNCTION tgsis.older_snapshots_check(text) IS
    'TG202 naming the other sessions of this database (and physical walsenders) whose backend_xmin is not after this transaction''s xid: their snapshot would read a table this transaction makes EMPTY; called by tgsis.store_in_rows and tgsis.store_class_in_rows at their start, as their last statement and at COMMIT (tgsis.older_snapshots_at_commit); autovacuum and this session''s own parallel workers left out';
