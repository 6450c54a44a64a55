-- tgsis.point_chunk_box(points): the box of a chunk of points (a G-map's vertices in chunks, role 'point'), the key of its GiST index.
-- docs/storage.md, "The points in chunks": a point chunk is a 2-D double
-- precision[] (slots x m, a hole a row of m NULLs). Its box is the cube of m
-- dimensions from the least to the greatest coordinate per axis over the
-- points that have a position: a hole, and a point with a NaN coordinate
-- (in no box: tgsis.md_vertices_in_box), are left out; NULL when no point is
-- left (such a chunk is in no box and no box query reads it) or m > 100 (the
-- cube type's limit). Computed from the chunk itself, never written by a
-- writer: tgsis.create_chunk_table indexes it as an expression
-- (<table>_chunk_<column>_box_idx), so every writer of chunks (the server's,
-- the client's COPY, the face, the merges, the conversion) keeps it right by
-- construction. Executable by PUBLIC: the index's expression, evaluated by
-- whoever writes the chunks, and tgsis.md_vertices_in_box's filter, run as
-- the caller.
CREATE FUNCTION tgsis.point_chunk_box(p_points double precision[])
RETURNS cube
LANGUAGE sql
IMMUTABLE
STRICT
PARALLEL SAFE
COST 1000
SET search_path FROM CURRENT
AS $$
    WITH v AS (SELECT u.x, (u.i - 1) / m.m AS s, (u.i - 1) % m.m AS k
                 FROM (SELECT array_length(p_points, 2) AS m) m,
                      unnest(p_points) WITH ORDINALITY AS u(x, i)
                WHERE array_ndims(p_points) = 2 AND m.m <= 100),
         bad AS (SELECT array_agg(DISTINCT v.s) AS s FROM v WHERE v.x IS NULL OR v.x = 'NaN'),
         axes AS (SELECT v.k, min(v.x) AS lo, max(v.x) AS hi FROM v, bad
                   WHERE bad.s IS NULL OR v.s <> ALL (bad.s) GROUP BY v.k)
    SELECT CASE WHEN count(*) > 0 THEN cube(array_agg(axes.lo ORDER BY axes.k), array_agg(axes.hi ORDER BY axes.k)) END FROM axes
$$;

COMMENT ON FUNCTION tgsis.point_chunk_box(double precision[]) IS
    'the box (cube of m dimensions) of a chunk of points (slots x m): least and greatest coordinate per axis over the points without a NULL or NaN coordinate; NULL when none is left or m > 100; the expression of the point chunk tables'' box index (tgsis.create_chunk_table), read by tgsis.md_vertices_in_box';
