-- tgsis.storage_rows(table): the relation with one row per stored row version of a versioned table, in the row table's columns then revision, lastrevs, revclosed.
-- <table>_ver itself, or for a model table stored in chunks its decoded view
-- tgsis.<table>_chunk_rows (tgsis.create_chunk_view: one row per present slot
-- of every chunk version, with that version's revision and lastrevs). What
-- reports rows reads it (diff_table, rows_at, conflict_rows,
-- conflict_discards): they compare rows by the row key (keycolumns) and
-- values, which the decoded view gives as <table>_ver did; a chunk version a
-- set sees shows all its rows in that set, so the same visibility tests
-- hold. Writers act on the storage (tgsis.storage_table) instead. The
-- registry row's form of tgsis.storage_row_versions (which says how).
CREATE FUNCTION tgsis.storage_rows(p_t tgsis.versioned_tables)
RETURNS text
LANGUAGE sql
STABLE
SET search_path = pg_catalog, pg_temp
AS $$
    SELECT tgsis.storage_row_versions(p_t.schemaname, p_t.tablename)  -- the one place that names it
$$;

REVOKE ALL ON FUNCTION tgsis.storage_rows(tgsis.versioned_tables) FROM PUBLIC;
-- (reached as the calling role by the invoker functions that read storage: diffs, rows_at, conflict reports)
GRANT EXECUTE ON FUNCTION tgsis.storage_rows(tgsis.versioned_tables) TO tgsis_reader;

COMMENT ON FUNCTION tgsis.storage_rows(tgsis.versioned_tables) IS
    'quoted name of the relation with one row per stored row version of a versioned table (row columns, revision, lastrevs, revclosed): <table>_ver, or tgsis.<table>_chunk_rows when the model table is stored in chunks';
