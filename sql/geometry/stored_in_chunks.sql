-- tgsis.stored_in_chunks(table): whether a model table's rows are stored in chunks (issue 40) rather than as rows.
-- The storage switch (tgsis.store_in_chunks) keeps the row table's definition,
-- without rows, as tgsis.<table>_shape and makes tgsis.<table> the face over
-- tgsis.<table>_chunk; the shape table is the marker. It is read from the
-- system catalogs, not from a flag in tgsis.model_tables, because the registry
-- is the script's own (never dumped) while the shape table, like the chunk
-- table, is dumped and restored with the data: a restored database says what
-- its storage is. Every reader and writer that reaches a table's storage
-- directly asks this (or tgsis.storage_table, which names the chunk table then).
CREATE FUNCTION tgsis.stored_in_chunks(p_table text)
RETURNS boolean
LANGUAGE sql
STABLE
PARALLEL SAFE
SET search_path = pg_catalog, pg_temp
AS $$
    SELECT to_regclass(format('tgsis.%I', p_table || '_shape')) IS NOT NULL
       AND to_regclass(format('tgsis.%I', p_table || '_chunk')) IS NOT NULL
$$;

COMMENT ON FUNCTION tgsis.stored_in_chunks(text) IS
    'whether the model table tgsis.<table> is stored in chunks (tgsis.<table>_chunk behind the face tgsis.<table>, its row definition kept as tgsis.<table>_shape: tgsis.store_in_chunks) rather than as rows';
