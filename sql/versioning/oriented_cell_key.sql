-- tgsis.oriented_cell_key(vertices): a cell's vertex ids ascending, then 1 when their order is an odd permutation, else 0.
-- Two rows are the same oriented cell exactly when their keys are equal: a
-- row rotated by an even permutation is the same cell, an odd one is the cell
-- turned over (docs/merge.md, "A side's edit"; tgsis.merge3 keys cells the
-- same way, and tgsis.mesh_changes with its sorting networks). The merge by
-- region in SQL (tgsis.mesh_merge_regions) compares and matches the few
-- changed cells with it; NULL for a NULL row.
CREATE FUNCTION tgsis.oriented_cell_key(p_vertices bigint[])
RETURNS bigint[]
LANGUAGE sql
IMMUTABLE
PARALLEL SAFE
AS $$
    SELECT ARRAY(SELECT x FROM unnest(p_vertices) AS u(x) ORDER BY x)
           || (SELECT count(*) % 2 FROM unnest(p_vertices) WITH ORDINALITY AS a(x, i)
                 JOIN unnest(p_vertices) WITH ORDINALITY AS b(y, j) ON a.i < b.j AND a.x > b.y)::bigint
     WHERE p_vertices IS NOT NULL
$$;

COMMENT ON FUNCTION tgsis.oriented_cell_key(bigint[]) IS
    'a cell''s vertex ids ascending followed by the parity of their order (1: odd permutation): equal keys, same oriented cell (as tgsis.merge3 compares cells)';
