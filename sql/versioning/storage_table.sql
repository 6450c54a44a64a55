-- tgsis.storage_table(schema, table): where a table's rows are physically stored: <table>_chunk when stored in chunks, <table>_ver when versioned, else the table.
-- A model table stored in chunks (tgsis.stored_in_chunks) is stored in
-- tgsis.<table>_chunk whether versioned or not: its chunk versions always
-- carry revision and lastrevs (docs/storage.md, "The relational face"); so
-- is a feature class's property table stored in chunks, in its own schema
-- (tgsis.store_class_in_chunks; tgsis.stored_in_chunks(schema, table)).
CREATE FUNCTION tgsis.storage_table(p_schema text, p_table text)
RETURNS text
LANGUAGE sql
STABLE
PARALLEL SAFE
AS $$
    SELECT format('%I.%I', p_schema,
                  CASE WHEN tgsis.stored_in_chunks(p_schema, p_table) THEN p_table || '_chunk'
                       WHEN EXISTS (SELECT FROM tgsis.versioned_tables t WHERE t.schemaname = p_schema AND t.tablename = p_table)
                       THEN p_table || '_ver' ELSE p_table END)
$$;

COMMENT ON FUNCTION tgsis.storage_table(text, text) IS
    'quoted schema.name of the relation that stores a table''s rows: <table>_chunk when the model table or the class''s property table is stored in chunks (tgsis.stored_in_chunks(schema, table)), <table>_ver when the table is versioned, else the table itself';
