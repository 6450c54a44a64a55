-- tgsis.storage_row_versions(schema, table, ids): the relation whose rows are a table's stored row versions (the row table's columns, then revision, lastrevs, revclosed).
-- The readers of a versioned storage that ask "the rows of these keys in
-- these revision sets" (the merges by region: tgsis.mesh_merge_work,
-- merge_solution_rows, merge_mesh_validity, merge_geometry_row, and
-- tgsis.conflict_discards) read one relation of rows with the row table's
-- columns and the versioning columns: <table>_ver when the rows are stored
-- as rows (tgsis.storage_table), the decoded chunk versions when a model
-- table or a class's property table is stored in chunks (tgsis.stored_in_chunks: a row per present slot
-- of every chunk version, with its chunk version's revision, lastrevs and
-- revclosed, so a visibility test on them reads as on rows). A filter on
-- geoid and on the versioning columns reaches the chunk table, one on a
-- local id does not (the id is computed from the chunk and the slot), so a
-- reader that wants rows of given ids passes them as p_ids: the relation is
-- then the decoding of only the chunks that hold them (chunk = id div the
-- table's chunksize; the caller still filters by id); without p_ids it is
-- the decoded view tgsis.<table>_chunk_rows. The decoding is the one of
-- the view (tgsis.chunk_decode_sql, of the chunks layer above this one:
-- named at run time, tests/test_sql_layers.py). One function names it, so
-- that every reader takes the same path. SECURITY DEFINER only to read the
-- decoding pieces (tgsis's internals): it reads no data, and what it names
-- is read with the caller's rights (the view and the chunk table's grants).
CREATE FUNCTION tgsis.storage_row_versions(p_schema text, p_table text, p_ids bigint[] DEFAULT NULL)
RETURNS text
LANGUAGE plpgsql
STABLE
SECURITY DEFINER
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_size bigint;
    v_dec  record;
    v_name text;
BEGIN
    IF NOT tgsis.stored_in_chunks(p_schema, p_table) THEN
        RETURN tgsis.storage_table(p_schema, p_table);
    END IF;
    v_name := CASE WHEN p_schema = 'tgsis' THEN p_table ELSE format('%I.%I', p_schema, p_table) END;  -- (tgsis.chunk_registry)
    IF p_ids IS NULL THEN
        RETURN format('%I.%I', p_schema, p_table || '_chunk_rows');
    END IF;
    EXECUTE format('SELECT r.chunksize FROM tgsis.%I($1) AS r', 'chunk_registry') INTO v_size USING v_name;
    EXECUTE format('SELECT d.select_list, d.arrays, d.aliases, d.present, d.joins FROM tgsis.%I($1, $2) AS d', 'chunk_decode_sql')
       INTO v_dec USING v_name, 'c';
    RETURN format('(SELECT %s, c.revision, c.lastrevs, c.revclosed FROM %I.%I c%s CROSS JOIN LATERAL unnest(%s) WITH ORDINALITY AS u(%s, o)'
                  ' WHERE %s AND c.chunk = ANY (%L::bigint[]))',
                  v_dec.select_list, p_schema, p_table || '_chunk', v_dec.joins, v_dec.arrays, v_dec.aliases, v_dec.present,
                  ARRAY(SELECT DISTINCT i / v_size FROM unnest(p_ids) AS i WHERE i >= 0 ORDER BY 1));
END
$$;

COMMENT ON FUNCTION tgsis.storage_row_versions(text, text, bigint[]) IS
    'SQL of the relation of a table''s stored row versions (the row table''s columns, then revision, lastrevs, revclosed): when the model table or a class''s property table is stored in chunks (tgsis.stored_in_chunks(schema, table)), its decoded chunk versions, only the chunks holding p_ids when given (else the view <table>_chunk_rows); else tgsis.storage_table''s relation (<table>_ver, or the table itself)';

-- internal to the merges' readers, not executable by PUBLIC (tests/test_function_grants.py); tgsis.mesh_merge_work runs it as the calling tgsis role
REVOKE ALL ON FUNCTION tgsis.storage_row_versions(text, text, bigint[]) FROM PUBLIC;
GRANT EXECUTE ON FUNCTION tgsis.storage_row_versions(text, text, bigint[]) TO tgsis_reader;
