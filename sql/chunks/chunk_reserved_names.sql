-- tgsis.chunk_reserved_names(): the names a class's property may not have when its table is stored in chunks.
-- A chunk table holds its own columns beside the property arrays (chunk,
-- revision, lastrevs, revclosed, holes, vbase, vtop), and the SQL this layer
-- generates (tgsis.rows_to_chunks, write_chunk_rows, chunk_face_write,
-- create_chunk_view, ...) names relations and columns of its own (slot, pad,
-- o, q, w, ...). A property of one of these names was left out of
-- the chunks without an error (revision, lastrevs, revclosed: the versioning
-- columns every row table leaves out) or broke the statements naming it, so
-- tgsis.chunk_columns refuses it by name (TG100) before anything is made. The
-- list is what a property of each name the layer's statements use did, found
-- by running the whole switch (store, read, write through the face, back to
-- rows) for each of them, every one- and two-letter name and the words of the
-- layer's SQL: these broke or lost values, the others worked
-- (tests/test_property_chunks.py keeps a sample of both).
CREATE FUNCTION tgsis.chunk_reserved_names()
RETURNS text[]
LANGUAGE sql
IMMUTABLE
PARALLEL SAFE
SET search_path = pg_catalog, pg_temp
AS $$
    SELECT ARRAY['chunk', 'revision', 'lastrevs', 'revclosed', 'holes', 'vbase', 'vtop',
                 'slot', 'pad', 'prev', 'last', 'fits', 'vmin', 'unchanged', 'umax', 'uslot', 'udel', 'vrev', 'vtid',
                 'vtoid', 'tgsis_old', 'label', 'o', 'q', 'w']::text[]
$$;

REVOKE ALL ON FUNCTION tgsis.chunk_reserved_names() FROM PUBLIC;

COMMENT ON FUNCTION tgsis.chunk_reserved_names() IS
    'the names a class''s property may not have when its table is stored in chunks: the chunk table''s own columns and the names the chunk layer''s statements use; tgsis.chunk_columns refuses them by name (TG100)';
