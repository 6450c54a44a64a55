-- tgsis.row_shape(table): the relation holding the row definition of a model table (columns, types, key, CHECKs, comments).
-- Before the storage switch it is the row storage (tgsis.storage_table: the
-- table or its <table>_ver); once the table is stored in chunks
-- (tgsis.stored_in_chunks) the row storage is gone and the switch kept its
-- definition, without rows, as tgsis.<table>_shape. The functions of this
-- layer read a table's columns, key, constraints and comments from here, so
-- that they work the same on both sides of the switch. The table is named as
-- tgsis.chunk_registry names it: a model table bare, a class's property table
-- schema-qualified (its shape <schema>.<table>_shape beside its chunk table).
CREATE FUNCTION tgsis.row_shape(p_table text)
RETURNS regclass
LANGUAGE sql
STABLE
SET search_path = pg_catalog, pg_temp
AS $$
    SELECT CASE WHEN to_regclass(format('%I.%I', r.schemaname, r.tablename || '_shape')) IS NOT NULL
                 AND to_regclass(format('%I.%I', r.schemaname, r.tablename || '_chunk')) IS NOT NULL
                THEN to_regclass(format('%I.%I', r.schemaname, r.tablename || '_shape'))
                ELSE to_regclass(tgsis.storage_table(r.schemaname, r.tablename)) END
      FROM tgsis.chunk_registry(p_table) r
$$;

REVOKE ALL ON FUNCTION tgsis.row_shape(text) FROM PUBLIC;

COMMENT ON FUNCTION tgsis.row_shape(text) IS
    'the relation holding the row definition of a table of tgsis.chunk_registry (a model table bare, a class''s property table schema-qualified): <schema>.<table>_shape (no rows) once it is stored in chunks, else its row storage (tgsis.storage_table); NULL when neither exists or the table is not registered';
