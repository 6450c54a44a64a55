-- tgsis.stored_in_chunks(schema, table): whether a model table or a feature class's property table is stored in chunks.
-- The two-argument form of tgsis.stored_in_chunks(table) for the functions of
-- the versioning layer, which name every versioned table by schema and name:
-- a model table (schema tgsis, tgsis.store_in_chunks) and the property table
-- of a feature class (its own schema, tgsis.store_class_in_chunks) are stored
-- in chunks when their row definition is kept as <table>_shape beside
-- <table>_chunk (the markers, dumped and restored with the data) and, out of
-- schema tgsis, <schema>.<table> is the face: a view with the chunk layer's
-- trigger (tgsis.create_chunk_face), which only its owner could have made.
-- Names alone would not do there: whoever may create tables in a class's
-- schema could make <table>_shape and <table>_chunk beside a versioned view,
-- and tgsis.storage_table would then name theirs. The chunk layer names the table bare
-- ('vrtx') in schema tgsis and schema-qualified ('public.rock_cellpros',
-- format('%I.%I')) otherwise (tgsis.chunk_registry).
CREATE FUNCTION tgsis.stored_in_chunks(p_schema text, p_table text)
RETURNS boolean
LANGUAGE sql
STABLE
PARALLEL SAFE
SET search_path = pg_catalog, pg_temp
AS $$
    SELECT to_regclass(format('%I.%I', p_schema, p_table || '_shape')) IS NOT NULL
       AND to_regclass(format('%I.%I', p_schema, p_table || '_chunk')) IS NOT NULL
       AND (p_schema = 'tgsis'
            OR EXISTS (SELECT FROM pg_trigger t
                        WHERE t.tgrelid = to_regclass(format('%I.%I', p_schema, p_table)) AND t.tgname = 'tgsis_chunk_face'))
$$;

COMMENT ON FUNCTION tgsis.stored_in_chunks(text, text) IS
    'whether <schema>.<table> is stored in chunks: a model table of schema tgsis (tgsis.store_in_chunks) or a feature class''s property table (tgsis.store_class_in_chunks): its row definition kept as <table>_shape beside <table>_chunk, the table itself a face (a view with the trigger tgsis_chunk_face)';
