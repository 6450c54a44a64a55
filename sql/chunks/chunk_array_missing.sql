-- tgsis.chunk_array_missing(chunk, column, value): 40001 for a chunk version whose property array is NULL (a snapshot older than the array).
-- tgsis.alter_chunk_table adds a property without rewriting the chunk table:
-- ADD COLUMN (no default, so no rewrite) and an UPDATE filling the new array
-- in every chunk version. A transaction whose snapshot predates that UPDATE
-- (REPEATABLE READ, SERIALIZABLE) still reads the chunk versions of before,
-- where the new array is NULL: reading the new property from them would give
-- NULL where every new snapshot reads the default, silently. The chunk
-- decoding (tgsis.chunk_decode_sql: the faces, the chunk views, the
-- versioning layer's storage readers) reads a property array only through
-- `CASE WHEN array IS NULL THEN tgsis.chunk_array_missing(...) ELSE value
-- END`, evaluated only where the column is read: the older snapshot reads the
-- other properties as before and is refused (40001, retry) for the new one.
-- A NULL array is nowhere else in the contract (docs/storage.md, "Property
-- chunks: the contract": every array present). STABLE, not IMMUTABLE: never
-- folded at plan time. Executable by everyone: a view's functions run with
-- the reader's rights; it tells nothing.
CREATE FUNCTION tgsis.chunk_array_missing(p_chunk text, p_column text, p_value anyelement)
RETURNS anyelement
LANGUAGE plpgsql
STABLE
PARALLEL SAFE
SET search_path = pg_catalog, pg_temp
AS $$
BEGIN
    RAISE EXCEPTION 'could not serialize access: % of % was added after this transaction''s snapshot', p_column, p_chunk
        USING ERRCODE = 'serialization_failure',
              DETAIL = format('The property %s was added (tgsis.add_property) by a transaction that committed after this one took its snapshot: this snapshot sees no value of it.', p_column),
              HINT = 'retry the transaction';
    RETURN p_value;
END
$$;

COMMENT ON FUNCTION tgsis.chunk_array_missing(text, text, anyelement) IS
    '40001 (serialization_failure): a chunk version''s property array is NULL, which only a snapshot older than tgsis.add_property''s fill of the new array sees; the chunk decoding (tgsis.chunk_decode_sql) calls it where such a column is read';
