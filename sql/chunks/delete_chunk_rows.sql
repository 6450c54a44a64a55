-- tgsis.delete_chunk_rows(table, columns, ints, floats): delete rows of a model table stored in chunks by their keys, for the calling role, set-based.
-- The bulk delete beside tgsis.insert_chunk_rows: the model-2 and model-3
-- check-in and merges by difference (src/tgsis/db/_state_write.py) delete the
-- rows whose key is gone or whose values changed, which through the face is a
-- chunk rewrite per row (tgsis.chunk_face_write). Here the keys (p_ints one row
-- per bigint key column, p_floats one per double precision key column, each
-- (columns x rows); p_columns names them, the bigint ones first: together
-- exactly the row table's primary key, tgsis.chunk_key and the chunk column)
-- go in one call of the one writer of chunk contents
-- (tgsis.write_chunk_rows, rows with _delete true: each touched chunk written
-- once, emptied ones deleted or closed; through tgsis.chunk_rows_write, the
-- writer it shares with insert_chunk_rows and replace_chunk_rows, which a
-- difference deleting and inserting rows of one table calls instead of
-- both) after the checks of a DELETE through
-- the face for the whole set: DELETE on the face (42501), the class's right to
-- delete the features' rows (tgsis.check_class_write 'UPDATE, DELETE'), the
-- version's write right and TG301 while an older revision is viewed, TG305 for
-- unversioned storage outside DEFAULT's working revision, revision 0 for the
-- features of classes without versioning, the objects not locked by another
-- version (TG303); 40001 for a snapshot older than the chunk table
-- (tgsis.chunk_snapshot_guard). The objects' write locks are taken
-- exclusively first (tgsis.object_write_lock: no face writer of them in
-- flight). A key that is not visible is skipped, as a DELETE skips it. The
-- objects are noted as changed in the working revision. Runs as tgsis's owner
-- (roles may not update chunk versions) with the keys in a temporary table of
-- its own (42501 for one the session made under that name). Refused by name
-- (TG100): a table not stored in chunks, columns that are not its key, arrays
-- of another shape, a NULL key, a key twice. Returns the number of rows
-- deleted (the visible keys among those given).
CREATE FUNCTION tgsis.delete_chunk_rows(p_table text, p_columns text[], p_ints bigint[], p_floats double precision[])
RETURNS bigint
LANGUAGE sql
VOLATILE
SECURITY DEFINER
SET search_path = pg_catalog, pg_temp
AS $$
    SELECT w.rows_deleted FROM tgsis.chunk_rows_write('delete', p_table, p_columns, p_ints, p_floats, NULL, NULL, NULL, NULL) AS w
$$;

REVOKE ALL ON FUNCTION tgsis.delete_chunk_rows(text, text[], bigint[], double precision[]) FROM PUBLIC;
GRANT EXECUTE ON FUNCTION tgsis.delete_chunk_rows(text, text[], bigint[], double precision[]) TO tgsis_reader;

COMMENT ON FUNCTION tgsis.delete_chunk_rows(text, text[], bigint[], double precision[]) IS
    'delete rows of a model table stored in chunks by their keys for the calling role, set-based (DELETE on the face, the class''s right, the version''s, object locks, the objects'' write locks): the bigint key columns then the double precision ones named, their values as (columns x keys) arrays; keys not visible skipped; every touched chunk written once by tgsis.write_chunk_rows; the objects noted as changed; returns the rows deleted';
