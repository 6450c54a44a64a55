-- tgsis.object_lock_limit(): how many objects a flush of a view UPDATE locks one by one.
-- The shared lock table holds max_locks_per_transaction x (max_connections +
-- max_prepared_transactions) locks for all sessions (64 x 100 by default),
-- so that one transaction taking one advisory lock per object of a large
-- UPDATE runs out of shared memory (53200). A flush that writes more
-- objects than half of max_locks_per_transaction (32 by default) takes the
-- class's lock in the version exclusively instead
-- (tgsis.object_class_lock_key); up to that many, the objects' own locks
-- shared, which let writers of other objects of the class go on.
CREATE FUNCTION tgsis.object_lock_limit()
RETURNS integer
LANGUAGE sql
STABLE
PARALLEL SAFE
AS $$
    SELECT greatest(1, pg_catalog.current_setting('max_locks_per_transaction')::integer / 2)
$$;

COMMENT ON FUNCTION tgsis.object_lock_limit() IS
    'the most objects a flush of an UPDATE through a versioned view locks one by one (half of max_locks_per_transaction): above it, the class''s lock in the version (tgsis.object_class_lock_key), exclusively';
