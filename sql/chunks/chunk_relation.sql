-- tgsis.chunk_relation(table, suffix): the quoted name of a relation the chunk layer makes beside a table: <schema>.<table><suffix>.
-- The chunk table (_chunk), its decoded view (_chunk_rows) and the row
-- definition kept at the switch (_shape) live in the table's own schema: tgsis
-- for a model table, the class's schema for a class's property table
-- (tgsis.chunk_registry). One function builds the name, so that no function
-- of the layer assumes schema tgsis. NULL when the table is not registered.
CREATE FUNCTION tgsis.chunk_relation(p_table text, p_suffix text)
RETURNS text
LANGUAGE sql
STABLE
SET search_path = pg_catalog, pg_temp
AS $$
    SELECT format('%I.%I', r.schemaname, r.tablename || p_suffix) FROM tgsis.chunk_registry(p_table) r
$$;

REVOKE ALL ON FUNCTION tgsis.chunk_relation(text, text) FROM PUBLIC;

COMMENT ON FUNCTION tgsis.chunk_relation(text, text) IS
    'the quoted name <schema>.<table><suffix> of a relation the chunk layer makes beside a table of tgsis.chunk_registry (suffix _chunk, _chunk_rows, _shape), in the table''s own schema; NULL for a table not registered';
