-- tgsis.chunk_snapshot_guard(chunk): true, or 40001 when the transaction's snapshot predates the chunk table (its file).
-- A chunk table rewritten by tgsis.alter_chunk_table (an added property,
-- ALTER ... USING) or made by a storage switch (tgsis.store_in_chunks,
-- tgsis.store_class_in_chunks: a new table filled in the switch's
-- transaction) after a transaction took its snapshot looks EMPTY to that
-- snapshot (REPEATABLE READ, SERIALIZABLE: PostgreSQL's caveat for rewriting
-- ALTERs; the new table's rows are a later transaction's). A read through the
-- face would give no row, silently. The test: the file the catalog names now
-- (pg_relation_filenode, the latest state) is not the relfilenode the
-- snapshot reads in pg_class (or the snapshot has no such pg_class row: the
-- table is newer), for the table or any partition of it
-- (tgsis.partition_chunk_storage; a partitioned parent has no file).
-- Called once per query by the chunk faces and chunk views (an InitPlan,
-- `WHERE (SELECT tgsis.chunk_snapshot_guard(...))`, tgsis.create_chunk_face,
-- tgsis.create_chunk_view), by the faces' write trigger
-- (tgsis.chunk_snapshot_check) and by the Python chunk readers in their
-- statement (tgsis.db._chunk_transfer). Under READ COMMITTED each statement's
-- snapshot is newer than the rewrite it waited for, and a transaction's own
-- rewrite is in its snapshot: nothing refused. VACUUM FULL, CLUSTER and
-- TRUNCATE change the file too: a snapshot older than them is refused as well
-- (40001, retry; after TRUNCATE rightly). Executable by everyone: whoever may
-- read a face runs it (a view's functions run with the reader's rights); it
-- tells nothing a role could not read in pg_class itself. In the versioning
-- layer (it reads only the catalog): tgsis.check_key_type asks it too.
CREATE FUNCTION tgsis.chunk_snapshot_guard(p_chunk regclass)
RETURNS boolean
LANGUAGE plpgsql
STABLE
PARALLEL SAFE
SET search_path = pg_catalog, pg_temp
AS $$
BEGIN
    -- the table itself, or its partitions; pg_class read with the transaction's snapshot (STABLE: the query's)
    IF EXISTS (SELECT FROM (SELECT p_chunk::oid AS relid UNION SELECT t.relid FROM pg_partition_tree(p_chunk) t) r
                 LEFT JOIN pg_class c ON c.oid = r.relid
                WHERE pg_relation_filenode(r.relid) IS NOT NULL
                  AND c.relfilenode IS DISTINCT FROM pg_relation_filenode(r.relid)) THEN
        RAISE EXCEPTION 'could not serialize access: % was rewritten or made after this transaction''s snapshot', p_chunk
            USING ERRCODE = 'serialization_failure',
                  DETAIL = format('%s was rewritten (a property added) or made (a storage switch) by a transaction that committed after this one took its snapshot: this snapshot sees it empty.',
                                  p_chunk),
                  HINT = 'retry the transaction';
    END IF;
    RETURN true;
END
$$;

COMMENT ON FUNCTION tgsis.chunk_snapshot_guard(regclass) IS
    'true, or 40001 (serialization_failure) when the transaction''s snapshot predates the file of the chunk table p_chunk or of a partition of it (rewritten by tgsis.alter_chunk_table adding a property, or made by a storage switch after the snapshot: the snapshot would read it empty); called once per query by the chunk faces and chunk views and by the Python chunk readers';
