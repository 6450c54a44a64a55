-- tgsis.chunk_row_key(table): the columns of a row's key in the face of a chunk table: the chunk table's
-- key columns before revision, the chunk column (the local id) in place of chunk (e.g. {geoid, vrtxid}).
-- tgsis.create_chunk_face writes them into the face's generated row function (<table>_face_row), so that
-- a row costs no catalog query; tgsis.chunk_face_queue asks here once per statement.
CREATE FUNCTION tgsis.chunk_row_key(p_table text)
RETURNS text[]
LANGUAGE sql
STABLE
PARALLEL SAFE
SET search_path = pg_catalog, pg_temp
AS $$
    SELECT array_agg(CASE WHEN a.attname = 'chunk' THEN r.chunkcolumn ELSE a.attname::text END ORDER BY a.attnum)
      FROM tgsis.chunk_registry(p_table) r
      JOIN pg_attribute a ON a.attrelid = tgsis.chunk_relation(p_table, '_chunk')::regclass
     WHERE a.attnum > 0
       AND a.attnum < (SELECT b.attnum FROM pg_attribute b
                        WHERE b.attrelid = tgsis.chunk_relation(p_table, '_chunk')::regclass AND b.attname = 'revision')
$$;

REVOKE ALL ON FUNCTION tgsis.chunk_row_key(text) FROM PUBLIC;

COMMENT ON FUNCTION tgsis.chunk_row_key(text) IS
    'the key columns of a row of the face of a chunk table (the chunk table''s key columns before revision, the chunk column in place of chunk): written into the face''s generated row function by tgsis.create_chunk_face';
