-- tgsis.object_write_prepare(table, objectclass, keys): the checks and locks a bulk writer of objects of tgsis.<table> makes before it writes.
-- Internal: the preamble shared by tgsis.write_object_rows and
-- tgsis.chunk_rows_write (which the SECURITY DEFINER entry points
-- delete_chunk_rows, insert_chunk_rows and replace_chunk_rows call), after
-- their own checks of the arguments and rights. In this order: for a
-- versioned table (tgsis.versioned_tables), the write right on the session's
-- version and TG301 while an older revision is viewed (tgsis.write_revision,
-- before any lock is taken), then TG303 for objects locked by another version
-- (tgsis.check_objects_unlocked); for unversioned storage, TG305 outside
-- DEFAULT's working revision (tgsis.plain_write_check); then the objects'
-- write locks, exclusively (tgsis.object_write_lock: no face writer of them
-- in flight), until the transaction ends.
CREATE FUNCTION tgsis.object_write_prepare(p_table text, p_objectclass text, p_keys text[])
RETURNS void
LANGUAGE plpgsql
VOLATILE
SET search_path = pg_catalog, pg_temp
AS $$
BEGIN
    IF EXISTS (SELECT FROM tgsis.versioned_tables t WHERE t.schemaname = 'tgsis' AND t.tablename = p_table) THEN
        PERFORM tgsis.write_revision();  -- TG002, TG301 before any lock is taken
        PERFORM tgsis.check_objects_unlocked(p_objectclass, p_keys);
    ELSE
        PERFORM tgsis.plain_write_check('tgsis', p_table);  -- TG305
    END IF;
    PERFORM tgsis.object_write_lock(p_objectclass, p_keys);
END
$$;

COMMENT ON FUNCTION tgsis.object_write_prepare(text, text, text[]) IS
    'internal: the preamble of the bulk writers of objects of tgsis.<table> (write_object_rows, chunk_rows_write): the version''s write right and TG301 (tgsis.write_revision) and TG303 (tgsis.check_objects_unlocked) when versioned, else TG305 (tgsis.plain_write_check); then the objects'' exclusive write locks (tgsis.object_write_lock)';

REVOKE ALL ON FUNCTION tgsis.object_write_prepare(text, text, text[]) FROM PUBLIC;
