-- tgsis.chunk_snapshot_check(): a chunk face's statement trigger refusing a write whose snapshot predates the chunk table's file or the face.
-- tgsis.alter_chunk_table adds a property by rewriting the chunk table
-- (ALTER ... USING), and a rewrite is not MVCC-safe: a transaction whose
-- snapshot was taken before it committed (REPEATABLE READ, SERIALIZABLE)
-- sees the table empty, so an UPDATE or DELETE through the face would find
-- no row and silently write nothing, and an INSERT would not see the rows
-- there. Fired BEFORE each INSERT, UPDATE and DELETE statement on the face
-- (tgsis.create_chunk_face; TG_ARGV[0]: the chunk table's qualified name):
-- when the file of the chunk table (or of one of its partitions) that the
-- catalog names now (pg_relation_filenode, the catalog's latest state) is
-- not the one the transaction's snapshot reads in pg_class, the table was
-- rewritten after the snapshot and the statement is refused with 40001
-- (serialization failure: the retry of the transaction sees the new table).
-- Under READ COMMITTED a statement's snapshot is taken after the lock it
-- waited for, and a transaction's own rewrite is in its snapshot: nothing is
-- refused. Other changes (GRANT) keep the file and refuse nothing.
-- The test is tgsis.chunk_snapshot_guard's (which the faces' reads run too).
-- Since plan H an add no longer rewrites (the new array is filled by an
-- UPDATE), but it makes the face again, as a rename and a drop do: a face
-- the snapshot does not know (no pg_class row for TG_RELID in it) was made
-- after the snapshot, whose catalog reads (the write's column list) no longer
-- match the face's row type: refused with 40001 too, not a type error.
-- Runs with the writer's rights (pg_class and pg_relation_filenode are
-- everyone's).
CREATE FUNCTION tgsis.chunk_snapshot_check()
RETURNS trigger
LANGUAGE plpgsql
VOLATILE
SET search_path = pg_catalog, pg_temp
AS $$
BEGIN
    -- the table or one of its partitions rewritten (or made) after the snapshot: 40001 (tgsis.chunk_snapshot_guard)
    PERFORM tgsis.chunk_snapshot_guard(TG_ARGV[0]::regclass);
    -- the face made again after the snapshot (an add, a rename, a drop of a property: tgsis.alter_chunk_table)
    IF NOT EXISTS (SELECT FROM pg_class c WHERE c.oid = TG_RELID) THEN   -- (read with the transaction's snapshot)
        RAISE EXCEPTION 'could not serialize access: %.% was made again after this transaction''s snapshot',
                        TG_TABLE_SCHEMA, TG_TABLE_NAME
            USING ERRCODE = 'serialization_failure',
                  DETAIL = 'A transaction that committed after this one took its snapshot changed the properties (add, rename or drop): this snapshot''s view of the columns is out of date.',
                  HINT = 'retry the transaction';
    END IF;
    RETURN NULL;
END
$$;

REVOKE ALL ON FUNCTION tgsis.chunk_snapshot_check() FROM PUBLIC;

COMMENT ON FUNCTION tgsis.chunk_snapshot_check() IS
    'BEFORE statement trigger of a chunk face (tgsis.create_chunk_face; TG_ARGV[0] the chunk table): refuses (40001) an INSERT, UPDATE or DELETE whose transaction snapshot predates the chunk table''s file or a partition''s (a storage switch made it, VACUUM FULL, TRUNCATE: such a snapshot sees the table empty; tgsis.chunk_snapshot_guard), or predates the face itself (made again by tgsis.alter_chunk_table: add, rename, drop of a property)';
