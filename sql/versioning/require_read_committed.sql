-- tgsis.require_read_committed(action): TG300 unless the transaction is READ COMMITTED.
-- Merge, refresh, set-based deletes and the check-in's check lock what they
-- work on (the versions' rows, the objects' write locks) and then read the
-- rows with statements that must see everything committed by the writers they
-- waited for. In READ COMMITTED every statement takes a new snapshot; in
-- REPEATABLE READ and SERIALIZABLE the snapshot is the transaction's first
-- one, and rows committed while they waited would be missed (a merge would
-- then move the version's base past changes it did not copy).
CREATE FUNCTION tgsis.require_read_committed(p_action text)
RETURNS void
LANGUAGE plpgsql
STABLE
AS $$
BEGIN
    IF current_setting('transaction_isolation') <> 'read committed' THEN
        RAISE EXCEPTION '% cannot run in a % transaction', p_action, upper(current_setting('transaction_isolation'))
            USING ERRCODE = 'TG300',
                  DETAIL = 'It waits for concurrent writers and must then see what they committed; the transaction''s '
                           'snapshot is older than that.',
                  HINT = 'run it in a READ COMMITTED transaction (PostgreSQL''s default)';
    END IF;
END
$$;

COMMENT ON FUNCTION tgsis.require_read_committed(text) IS
    'raise TG300 naming the action unless the transaction''s isolation level is READ COMMITTED (merge, refresh, set-based deletes, check-in checks must see what the writers they waited for committed)';
