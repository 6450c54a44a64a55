-- tgsis.object_class_lock_key(objectclass, versionid): the advisory lock key of all objects of a class in one version.
-- The escalation of tgsis.object_lock_key for writes of many objects at
-- once. Every bulk writer of objects of the class (tgsis.object_write_lock)
-- holds it shared beside the objects' own locks, so that a flush of an
-- UPDATE through a versioned view that writes more objects than
-- tgsis.object_lock_limit() can take this one lock exclusively instead of
-- one shared lock per object: it waits for every bulk writer of the class
-- in the version in flight, and they wait for it, as they would for its
-- per-object locks (the shared lock table has room for some
-- max_locks_per_transaction locks per connection: one lock per object of
-- a 50,000-row UPDATE fails with 53200). The hash is seeded by the version,
-- as the objects' locks, and its text cannot be an object's
-- (tgsis.object_lock_key hashes 'class:key').
CREATE FUNCTION tgsis.object_class_lock_key(p_objectclass text, p_versionid integer)
RETURNS bigint
LANGUAGE sql
IMMUTABLE
PARALLEL SAFE
AS $$
    SELECT pg_catalog.hashtextextended('tgsis.object_class_lock ' || p_objectclass, p_versionid)
$$;

COMMENT ON FUNCTION tgsis.object_class_lock_key(text, integer) IS
    'advisory lock key (64-bit hash) of all objects of a class in a version: held shared by every bulk writer (tgsis.object_write_lock), exclusively by a view UPDATE writing more objects than tgsis.object_lock_limit()';
