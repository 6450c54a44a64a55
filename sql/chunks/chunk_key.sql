-- tgsis.chunk_key(table): the key columns of a table's chunks before chunk, as a list (geoid; geoid, times; _geoid).
-- The chunk key is a list (docs/storage.md, "Chunks and the mapping of ids"):
-- model 1's chunks are keyed (geoid, chunk), model 2's times_vrtx and
-- times_trgl (geoid, times, chunk), a class's property table (_geoid, chunk).
-- It is the row table's primary key without its local-id column and without
-- revision, in key order, read from the live row definition by
-- tgsis.chunk_columns (role 'key'), never typed: every function of the layer
-- that groups, locks or compares chunks by key takes it from here or from the
-- same rows of tgsis.chunk_columns. A double precision key (times) is compared
-- as the rows' primary key compares it, with the float8 = operator: -0.0 and
-- 0.0 are one key, and so are all NaNs; what a chunk stores is the bits of the
-- key as first written (tgsis.write_chunk_rows refuses by name a row whose key
-- is equal but not the same bits). TG200 / TG100 as tgsis.chunk_columns.
CREATE FUNCTION tgsis.chunk_key(p_table text)
RETURNS text[]
LANGUAGE sql
STABLE
SET search_path = pg_catalog, pg_temp
AS $$
    SELECT ARRAY(SELECT c.name FROM tgsis.chunk_columns(p_table) c WHERE c.role = 'key' ORDER BY c.keyorder)
$$;

REVOKE ALL ON FUNCTION tgsis.chunk_key(text) FROM PUBLIC;

COMMENT ON FUNCTION tgsis.chunk_key(text) IS
    'the key columns of a table''s chunks before chunk, in key order (the row table''s primary key without its local id and revision, from tgsis.chunk_columns): {geoid} for model 1, {geoid,times} for model 2''s times_vrtx and times_trgl, {_geoid} for a class''s property table; TG200/TG100 as tgsis.chunk_columns';
