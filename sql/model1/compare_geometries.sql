-- tgsis.compare_geometries(old, new): how many vertices and cells of two stored geometries were kept, removed and added, with the ids of the removed and added ones.
-- Six rows, always in this order: vertex kept, removed, added; cell kept,
-- removed, added. ids: the old ids of removed rows, the new ids of added
-- ones (ascending; '{}' when none), NULL for kept rows (the pairs can be
-- millions: tgsis.geometry_changes lists them).
CREATE FUNCTION tgsis.compare_geometries(p_old bigint, p_new bigint)
RETURNS TABLE (element text, status text, count bigint, ids bigint[])
LANGUAGE sql
STABLE
AS $$
    WITH c AS (
        SELECT c.element, c.status, count(*) AS n,
               array_agg(coalesce(c.old_id, c.new_id)) FILTER (WHERE c.status <> 'kept') AS ids
          FROM tgsis.geometry_changes(p_old, p_new) c
         GROUP BY c.element, c.status)
    SELECT f.element, f.status, coalesce(c.n, 0),
           CASE WHEN f.status <> 'kept' THEN ARRAY(SELECT i FROM unnest(c.ids) AS i ORDER BY i) END
      FROM (VALUES (1, 'vertex', 'kept'), (2, 'vertex', 'removed'), (3, 'vertex', 'added'),
                   (4, 'cell', 'kept'), (5, 'cell', 'removed'), (6, 'cell', 'added')) AS f(o, element, status)
      LEFT JOIN c ON c.element = f.element AND c.status = f.status
     ORDER BY f.o
$$;

COMMENT ON FUNCTION tgsis.compare_geometries(bigint, bigint) IS
    'what changed from one static geometry to another of its geotype, in the session''s version: six rows (vertex|cell, kept|removed|added) with the count and the ids (old ids removed, new ids added, ascending; NULL for kept); see tgsis.geometry_changes for the rows themselves';
