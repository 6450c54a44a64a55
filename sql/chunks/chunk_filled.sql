-- tgsis.chunk_filled(value, length, holes): a property chunk's array holding one value at every present slot and NULL at every hole.
-- The form a property added to a class stored in chunks takes in every chunk
-- version (tgsis.alter_chunk_table): docs/storage.md, "Property chunks: the
-- contract" asks of each property array that it be one-dimensional from 1, of
-- the chunk's length, NULL at every hole (holes is the only hole marker, a
-- present slot may hold NULL). p_value NULL gives the all-NULL array of the
-- length. A function, not a subquery, because ALTER TABLE ... USING (which
-- rewrites the chunk table once, firing no row trigger) allows no subquery.
CREATE FUNCTION tgsis.chunk_filled(p_value anyelement, p_length integer, p_holes smallint[])
RETURNS anyarray
LANGUAGE sql
IMMUTABLE
PARALLEL SAFE
SET search_path = pg_catalog, pg_temp
AS $$
    SELECT CASE WHEN p_holes IS NULL OR p_value IS NULL THEN array_fill(p_value, ARRAY[p_length])
                ELSE ARRAY(SELECT CASE WHEN s = ANY (p_holes) THEN NULL ELSE p_value END
                             FROM generate_series(1, p_length) AS g(s) ORDER BY s) END
$$;

REVOKE ALL ON FUNCTION tgsis.chunk_filled(anyelement, integer, smallint[]) FROM PUBLIC;

COMMENT ON FUNCTION tgsis.chunk_filled(anyelement, integer, smallint[]) IS
    'an array of p_length elements: p_value at every slot but those of p_holes (NULL there); the form of a property added to a class stored in chunks, in every chunk version (tgsis.alter_chunk_table)';
