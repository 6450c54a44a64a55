-- tgsis.row_shape(table): the relation holding the row definition of a model table (columns, types, key, CHECKs, comments).
-- Before the storage switch it is the row storage (tgsis.storage_table: the
-- table or its <table>_ver); once the table is stored in chunks
-- (tgsis.stored_in_chunks) the row storage is gone and the switch kept its
-- definition, without rows, as tgsis.<table>_shape. The functions of this
-- layer read a table's columns, key, constraints and comments from here, so
-- that they work the same on both sides of the switch.
CREATE FUNCTION tgsis.row_shape(p_table text)
RETURNS regclass
LANGUAGE sql
STABLE
SET search_path = pg_catalog, pg_temp
AS $$
    SELECT CASE WHEN tgsis.stored_in_chunks(p_table) THEN to_regclass(format('tgsis.%I', p_table || '_shape'))
                ELSE to_regclass(tgsis.storage_table('tgsis', p_table)) END
$$;

REVOKE ALL ON FUNCTION tgsis.row_shape(text) FROM PUBLIC;

COMMENT ON FUNCTION tgsis.row_shape(text) IS
    'the relation holding a model table''s row definition: tgsis.<table>_shape (no rows) once it is stored in chunks, else its row storage (tgsis.storage_table); NULL when neither exists';
