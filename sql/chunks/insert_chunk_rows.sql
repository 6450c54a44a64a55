-- tgsis.insert_chunk_rows(table, columns, ints, floats, bools): insert new rows of a model table stored in chunks, for the calling role, set-based.
-- The bulk insert of the tables whose writers COPY rows (model 2's
-- times_vrtx and times_trgl: tgsis.insert_series, add_instant, the check-in
-- and merges of model 2; src/tgsis/db/_transfer.py, Storage.copy): once the
-- table is stored in chunks its name is a face, and an INSERT through it
-- rewrites a chunk per row (tgsis.chunk_face_write). Here the rows (p_ints one
-- row per bigint, integer or smallint column, p_floats one per double precision column, p_bools
-- one per boolean column, each (columns x rows), the columns named by
-- p_columns: the bigint ones, the double ones, then the boolean ones; every
-- column of the row table but those that may be NULL, which are NULL when not
-- named, as a COPY leaves them: a G-map dart's acellid and positive) are
-- written by one call of
-- the one writer of chunk contents (tgsis.write_chunk_rows: each touched
-- chunk once, in the working revision; through tgsis.chunk_rows_write, the
-- writer it shares with delete_chunk_rows and replace_chunk_rows) after the checks of an INSERT through
-- the face: INSERT on the face (42501), the class's write right on every
-- object (tgsis.check_class_write), the write right on the session's version
-- and TG301 while an older revision is viewed (tgsis.write_revision), TG305
-- for unversioned storage outside DEFAULT's working revision, revision 0 for
-- features of classes without versioning (tgsis.write_chunk_rows), the
-- objects not locked by another version (TG303). The objects' write locks are
-- taken exclusively (tgsis.object_write_lock: no face write of them in
-- flight), then a row whose key is visible already is refused as the face
-- and the rows' primary key refuse it (23505 naming <table>_pkey; a COPY into
-- rows would fail the same way): an insert never replaces a row. The objects
-- are noted as changed in the working revision. As write_object_rows, it runs
-- as tgsis's owner (roles may not update chunk versions) with the rows in a
-- temporary table of its own (42501 for one the session made under that
-- name). Refused by name (TG100): a table not stored in chunks, columns that
-- are not the table's, arrays of another shape; and what
-- tgsis.write_chunk_rows refuses (NULL values, negative ids, a key twice, a
-- key equal to a stored one of other bits, a CHECK of the row table).
-- Returns the number of chunks written.
CREATE FUNCTION tgsis.insert_chunk_rows(p_table text, p_columns text[], p_ints bigint[], p_floats double precision[],
                                        p_bools boolean[] DEFAULT NULL)
RETURNS bigint
LANGUAGE sql
VOLATILE
SECURITY DEFINER
SET search_path = pg_catalog, pg_temp
AS $$
    SELECT w.chunks_written FROM tgsis.chunk_rows_write('insert', p_table, NULL, NULL, NULL, p_columns, p_ints, p_floats, p_bools) AS w
$$;

COMMENT ON FUNCTION tgsis.insert_chunk_rows(text, text[], bigint[], double precision[], boolean[]) IS
    'insert new rows of a model table stored in chunks for the calling role, set-based (INSERT on the face, the class''s write right, the version''s, object locks): the bigint columns, the double precision columns, then the boolean columns named (a column that may be NULL may be left out: NULL), their values as (columns x rows) arrays; a key visible already is 23505 as on rows; every touched chunk rewritten once by tgsis.write_chunk_rows; the objects noted as changed; returns the chunks written';
