-- tgsis.object_write_lock(objectclass, keys): lock objects of the session's version for a bulk write until the transaction ends.
-- Exclusive, in key order (two bulk writers of the same objects cannot
-- deadlock). It waits for the transactions that wrote rows of these objects
-- through the versioned views (they hold tgsis.object_lock_key shared), and
-- such writes wait for it: check-in, save by difference and set-based
-- deletes then read the object's state, decide and write with no
-- concurrent change in between (no lost update, no resurrected row).
-- First, the class's lock in the version shared (tgsis.object_class_lock_key):
-- a view UPDATE writing too many objects to lock them one by one takes it
-- exclusively instead, and bulk writers wait for it as for its objects'
-- locks (and it for them); bulk writers do not wait for each other there.
CREATE FUNCTION tgsis.object_write_lock(p_objectclass text, p_keys text[])
RETURNS void
LANGUAGE plpgsql
VOLATILE
AS $$
DECLARE
    v_versionid integer := tgsis.version_id(tgsis.get_working_version());
BEGIN
    PERFORM pg_catalog.pg_advisory_xact_lock_shared(tgsis.object_class_lock_key(p_objectclass, v_versionid));
    PERFORM pg_catalog.pg_advisory_xact_lock(tgsis.object_lock_key(p_objectclass, k, v_versionid))
       FROM (SELECT DISTINCT k FROM unnest(p_keys) AS u(k) WHERE k IS NOT NULL ORDER BY k) AS s;
END
$$;

COMMENT ON FUNCTION tgsis.object_write_lock(text, text[]) IS
    'take the exclusive object write locks (tgsis.object_lock_key) of objects of a class in the session''s version, in key order, after the class''s lock in the version shared (tgsis.object_class_lock_key), until the transaction ends: waits for open view writers of them, who then wait for it';
