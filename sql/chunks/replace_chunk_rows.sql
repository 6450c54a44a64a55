-- tgsis.replace_chunk_rows(table, delete columns, delete ints, delete floats, columns, ints, floats, bools): delete rows of a model table stored in chunks by key and insert new ones, in one write of each touched chunk, for the calling role.
-- What tgsis.delete_chunk_rows then tgsis.insert_chunk_rows do, in one call:
-- the Python check-in and merges of models 2 and 3 by difference
-- (src/tgsis/db/_state_write.py) delete the rows whose key went or whose
-- values changed and insert the new and changed ones; through the two calls
-- a changed chunk was written twice (two chunk versions, the first dead at
-- once), here once. The keys to delete (p_delete_columns, the key columns,
-- the bigint ones first; p_delete_ints, p_delete_floats their values, each
-- (columns x keys)) are delete_chunk_rows' arguments, the rows to insert
-- (p_columns, p_ints, p_floats, p_bools) insert_chunk_rows'. The same checks,
-- in the same order (the keys' then the rows'), the same answers
-- (tgsis.chunk_rows_write): keys not visible are skipped, a row whose key is
-- visible and not deleted by this call is 23505, a key deleted and inserted
-- again is replaced. Returns the rows deleted (the visible keys among those
-- given) and the chunks written.
CREATE FUNCTION tgsis.replace_chunk_rows(p_table text,
                                         p_delete_columns text[], p_delete_ints bigint[], p_delete_floats double precision[],
                                         p_columns text[], p_ints bigint[], p_floats double precision[],
                                         p_bools boolean[] DEFAULT NULL,
                                         OUT rows_deleted bigint, OUT chunks_written bigint)
LANGUAGE sql
VOLATILE
SECURITY DEFINER
SET search_path = pg_catalog, pg_temp
AS $$
    SELECT w.rows_deleted, w.chunks_written
      FROM tgsis.chunk_rows_write('replace', p_table, p_delete_columns, p_delete_ints, p_delete_floats,
                                  p_columns, p_ints, p_floats, p_bools) AS w
$$;

REVOKE ALL ON FUNCTION tgsis.replace_chunk_rows(text, text[], bigint[], double precision[], text[], bigint[], double precision[], boolean[]) FROM PUBLIC;
GRANT EXECUTE ON FUNCTION tgsis.replace_chunk_rows(text, text[], bigint[], double precision[], text[], bigint[], double precision[], boolean[]) TO tgsis_reader;

COMMENT ON FUNCTION tgsis.replace_chunk_rows(text, text[], bigint[], double precision[], text[], bigint[], double precision[], boolean[]) IS
    'delete rows of a model table stored in chunks by key and insert new ones for the calling role, in one write of each touched chunk (what tgsis.delete_chunk_rows then tgsis.insert_chunk_rows do, with their checks and answers; a key deleted and inserted again is replaced): returns the rows deleted and the chunks written';
