-- tgsis.storage_calls: which runner tgsis's definer code is calling now, per backend.
-- A table's runner (<table>_ver_run()) may be called by tgsis_nobody, as
-- which tgsis.storage_hop runs. Code running as tgsis_nobody could then call
-- the runner of any table, e.g. a runner its owner made SECURITY INVOKER,
-- calling another owner's runner. So each runner first asks
-- tgsis.check_storage_call whether tgsis itself is calling it right now in
-- this backend: tgsis.storage_run records the call here (only tgsis's owner
-- may write this table) and removes it when the runner returns. Rows live
-- only as long as one call; UNLOGGED, nothing to keep across a crash.
CREATE UNLOGGED TABLE tgsis.storage_calls (
    backend integer PRIMARY KEY,
    runner  text    NOT NULL
);

COMMENT ON TABLE tgsis.storage_calls IS
    'the runner <schema>.<table>_ver_run() tgsis is calling now in each backend (tgsis.storage_run); runners refuse any other caller (tgsis.check_storage_call)';
COMMENT ON COLUMN tgsis.storage_calls.backend IS 'pg_backend_pid() of the session';
COMMENT ON COLUMN tgsis.storage_calls.runner IS 'the runner called, as quoted schema.name';
