-- tgsis.storage_row_versions(schema, table): the relation whose rows are a table's stored row versions, one per row and revision, with revision, lastrevs and revclosed.
-- The readers of a versioned storage that ask "the rows of these keys in
-- these revision sets" (the merges by region: tgsis.mesh_merge_work,
-- merge_solution_rows, merge_mesh_validity, merge_geometry_row) read one
-- relation of rows with the row table's columns and the versioning columns:
-- <table>_ver when the rows are stored as rows (tgsis.storage_table), the
-- decoded view tgsis.<table>_chunk_rows when a model table is stored in
-- chunks (tgsis.stored_in_chunks: a row per present slot of every chunk
-- version, with its chunk version's revision, lastrevs and revclosed, so a
-- visibility test on them reads as on rows). A filter on geoid and on the
-- versioning columns reaches the chunk table (only the chunk versions it
-- keeps are decoded); one on a local id does not (the object's chunks that
-- pass the other filters are decoded: docs/performance.md, the merge
-- section). One function names it, so that every reader takes the same
-- path.
CREATE FUNCTION tgsis.storage_row_versions(p_schema text, p_table text)
RETURNS text
LANGUAGE sql
STABLE
PARALLEL SAFE
SET search_path = pg_catalog, pg_temp
AS $$
    SELECT CASE WHEN p_schema = 'tgsis' AND tgsis.stored_in_chunks(p_table) THEN format('tgsis.%I', p_table || '_chunk_rows')
                ELSE tgsis.storage_table(p_schema, p_table) END
$$;

COMMENT ON FUNCTION tgsis.storage_row_versions(text, text) IS
    'quoted schema.name of the relation of a table''s stored row versions (the row table''s columns, then revision, lastrevs, revclosed): tgsis.<table>_chunk_rows, the decoded chunks, when the model table is stored in chunks (tgsis.stored_in_chunks), else tgsis.storage_table''s relation (<table>_ver, or the table itself)';

-- internal to the merges' readers, not executable by PUBLIC (tests/test_function_grants.py); tgsis.mesh_merge_work runs it as the calling tgsis role
REVOKE ALL ON FUNCTION tgsis.storage_row_versions(text, text) FROM PUBLIC;
GRANT EXECUTE ON FUNCTION tgsis.storage_row_versions(text, text) TO tgsis_reader;
