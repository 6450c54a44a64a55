-- tgsis.object_lock_key(objectclass, key, versionid): the advisory lock key of one object in one version.
-- Writes through versioned views hold it shared for their transaction, the
-- bulk writers of an object (check-in, save by difference, set-based
-- deletes) exclusively (tgsis.object_write_lock): a bulk writer decides from
-- the object's state with no view writer of it in flight, and a view writer
-- that comes later finds its state changed. Writers of the object in other
-- versions do not wait for each other: the version is the hash's seed.
CREATE FUNCTION tgsis.object_lock_key(p_objectclass text, p_key text, p_versionid integer)
RETURNS bigint
LANGUAGE sql
IMMUTABLE
PARALLEL SAFE
AS $$
    SELECT pg_catalog.hashtextextended(p_objectclass || ':' || p_key, p_versionid)
$$;

COMMENT ON FUNCTION tgsis.object_lock_key(text, text, integer) IS
    'advisory lock key (64-bit hash) of object p_key of a class in a version: held shared by view writes, exclusively by bulk writers of the object';
