-- tgsis.storage_cells_on(table, vertex ids): the relation of a cell table's stored row versions that may stand on given vertices.
-- The one-ring readers of the merges by region (tgsis.mesh_merge_work's margin,
-- tgsis.merge_mesh_validity's cells near the change, the Python reader of the
-- change) ask "the cells on these vertices". On rows the storage's vertex BRIN
-- answers it (tgsis.cells_on_vertices_sql, which the caller still applies). A
-- table stored in chunks has no index from a vertex to its cells: decoding every
-- chunk of the object read the whole object for a small change. So each chunk
-- carries vtop, a bound of its vertex ids (tgsis.chunk_encoding_checks), and
-- vbase, the least of them: only the chunk versions whose [vbase, vtop] holds
-- one of p_vertex_ids are decoded (a wide chunk, vbase NULL: those whose vtop is
-- at least one of them). The test is width_bucket over the sorted ids (a binary
-- search in C per chunk), exact for the interval, so no chunk holding such a
-- cell is skipped; the caller filters the decoded rows by the ids exactly, as
-- on rows. Otherwise as tgsis.storage_row_versions (the row table's columns,
-- then revision, lastrevs, revclosed; the decoding of tgsis.chunk_decode_sql,
-- named at run time: the chunks layer is below this one). Not stored in chunks,
-- or a table without vertex-id columns: tgsis.storage_row_versions' relation.
-- No ids (none but NULLs): a relation of no rows. SECURITY DEFINER only to
-- read the decoding pieces: what it names is read with the caller's rights.
CREATE FUNCTION tgsis.storage_cells_on(p_table text, p_vertex_ids bigint[])
RETURNS text
LANGUAGE plpgsql
STABLE
SECURITY DEFINER
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_dec record;
    v_ids bigint[];
BEGIN
    IF NOT tgsis.stored_in_chunks(p_table)
       OR NOT EXISTS (SELECT FROM tgsis.model_tables t WHERE t.tablename = p_table AND cardinality(t.chunkrefs) > 0) THEN
        RETURN tgsis.storage_row_versions('tgsis', p_table);
    END IF;
    v_ids := ARRAY(SELECT DISTINCT i FROM unnest(p_vertex_ids) AS i WHERE i IS NOT NULL ORDER BY 1);
    EXECUTE format('SELECT d.select_list, d.arrays, d.aliases, d.present, d.joins FROM tgsis.%I($1, $2) AS d', 'chunk_decode_sql')
       INTO v_dec USING p_table, 'c';
    -- width_bucket(x, ids): how many of the sorted ids are at most x
    RETURN format('(SELECT %s, c.revision, c.lastrevs, c.revclosed FROM tgsis.%I c%s CROSS JOIN LATERAL unnest(%s) WITH ORDINALITY AS u(%s, o)'
                  ' WHERE %s AND width_bucket(c.vtop, %L::bigint[])'
                  ' > CASE WHEN c.vbase IS NULL THEN 0 ELSE width_bucket(c.vbase - 1, %L::bigint[]) END)',
                  v_dec.select_list, p_table || '_chunk', v_dec.joins, v_dec.arrays, v_dec.aliases, v_dec.present, v_ids, v_ids);
END
$$;

COMMENT ON FUNCTION tgsis.storage_cells_on(text, bigint[]) IS
    'SQL of the relation of a cell table''s stored row versions (the row table''s columns, then revision, lastrevs, revclosed) that may stand on the given vertices: stored in chunks, the decoded chunk versions whose [vbase, vtop] holds one of the ids (the caller filters the rows exactly); else tgsis.storage_row_versions'' relation';

-- internal to the merges' readers, not executable by PUBLIC (tests/test_function_grants.py); the tgsis roles run it as themselves
REVOKE ALL ON FUNCTION tgsis.storage_cells_on(text, bigint[]) FROM PUBLIC;
GRANT EXECUTE ON FUNCTION tgsis.storage_cells_on(text, bigint[]) TO tgsis_reader;
