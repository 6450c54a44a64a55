-- tgsis.chunk_face_work(table, kind): the name of a session's work table (or setting) of the writes through
-- the face of a chunk table (docs/storage.md, "The relational face over chunks", Writes).
-- kind: 'rows' and 'dels' (the rows kept by the face's row trigger, its generated function
-- <table>_face_row, tgsis.create_chunk_face), 'queue' and 'now' (tgsis.chunk_face_write's), each
-- pg_temp.tgsis_face_<kind>_<tag>; 'deleted' the transaction's setting tgsis.face_deleted_<tag> (the
-- statement deletes or moved keys away). The tag is the first 16 hex digits of the md5 of the chunk
-- registry's name of the table (tgsis.chunk_registry: 'vrtx', a class's 'schema.table'): stable across
-- pg_dump/restore and a rename of the face (the generated row function has the names written in its static
-- SQL; a view's oid, their tag before, changes at a restore), one per chunk table.
CREATE FUNCTION tgsis.chunk_face_work(p_table text, p_kind text)
RETURNS text
LANGUAGE sql
IMMUTABLE
PARALLEL SAFE
SET search_path = pg_catalog, pg_temp
AS $$
    SELECT CASE WHEN p_kind = 'deleted' THEN 'tgsis.face_deleted_' || left(md5(p_table), 16)
                ELSE format('pg_temp.%I', 'tgsis_face_' || p_kind || '_' || left(md5(p_table), 16)) END
$$;

REVOKE ALL ON FUNCTION tgsis.chunk_face_work(text, text) FROM PUBLIC;

COMMENT ON FUNCTION tgsis.chunk_face_work(text, text) IS
    'the name of a session''s work table of the writes through the face of a chunk table (kind rows, dels, queue, now: pg_temp.tgsis_face_<kind>_<the first 16 hex digits of md5(table)>) or, kind deleted, of its setting tgsis.face_deleted_<tag>; stable across pg_dump/restore, as the face''s generated row function names them in static SQL';
