-- tgsis.chunk_reserved_names(): the names a class's property may not have when its table is stored in chunks.
-- A chunk table holds its own columns beside the property arrays (chunk,
-- revision, lastrevs, revclosed, holes, vbase, vtop), and the SQL this layer
-- generates (tgsis.rows_to_chunks, write_chunk_rows, chunk_face_write,
-- create_chunk_view, ...) names relations and columns of its own (slot, pad,
-- state, ...; its one-letter relation names are refused by pattern
-- in tgsis.chunk_columns). A property of one of these names was left out of
-- the chunks without an error (revision, lastrevs, revclosed: the versioning
-- columns every row table leaves out) or broke the statements naming it, so
-- tgsis.chunk_columns refuses it by name (TG100) before anything is made. The
-- list is read from the layer's own statements (tests/test_property_chunks.py
-- runs the whole switch for each name and for near names that must work).
CREATE FUNCTION tgsis.chunk_reserved_names()
RETURNS text[]
LANGUAGE sql
IMMUTABLE
PARALLEL SAFE
SET search_path = pg_catalog, pg_temp
AS $$
    SELECT ARRAY['chunk', 'revision', 'lastrevs', 'revclosed', 'holes', 'vbase', 'vtop',
                 'slot', 'pad', 'state', 'prev', 'last', 'fits', 'fit', 'vmin', 'revs', 'rows', 'sets', 'wsets', 'ev0',
                 'old', 'moved', 'fresh', 'upsert', 'upd', 'del', 'ins', 'cls', 'same', 'unchanged', 'umax', 'uslot',
                 'udel', 'vrev', 'vtid', 'vtoid', 'live', 'kept', 'ord', 'idx', 'col', 'con', 'pk', 'attnum', 'keyorder',
                 'name', 'role', 'typename', 'colorder', 'tgsis_old', 'tgsis_new_chunks', 'wfit', 'present', 'decoded',
                 'mine', 'absent', 'changed', 'gone', 'object', 'label', 'note', 'expr', 'qual', 'def', 'withcheck',
                 'storage', 'schema', 'table', 'read', 'first',
                 'ch', 'en', 'ev', 'ug', 'ws', 'pt', 'rw', 'id']::text[]
$$;

REVOKE ALL ON FUNCTION tgsis.chunk_reserved_names() FROM PUBLIC;

COMMENT ON FUNCTION tgsis.chunk_reserved_names() IS
    'the names (besides single lower-case letters) a class''s property may not have when its table is stored in chunks: the chunk table''s own columns and the names the chunk layer''s statements use; tgsis.chunk_columns refuses them by name (TG100)';
