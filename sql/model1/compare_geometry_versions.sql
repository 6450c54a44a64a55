-- tgsis.compare_geometry_versions(geoid, old_version, new_version, old_revision, new_revision): tgsis.compare_geometries of one geometry between two versions or revisions.
-- The same six rows, counted over tgsis.geometry_version_changes.
CREATE FUNCTION tgsis.compare_geometry_versions(
    p_geoid        bigint,
    p_old_version  text,
    p_new_version  text,
    p_old_revision integer DEFAULT NULL,
    p_new_revision integer DEFAULT NULL)
RETURNS TABLE (element text, status text, count bigint, ids bigint[])
LANGUAGE sql
STABLE
AS $$
    WITH c AS (
        SELECT c.element, c.status, count(*) AS n,
               array_agg(coalesce(c.old_id, c.new_id)) FILTER (WHERE c.status <> 'kept') AS ids
          FROM tgsis.geometry_version_changes(p_geoid, p_old_version, p_new_version, p_old_revision, p_new_revision) c
         GROUP BY c.element, c.status)
    SELECT f.element, f.status, coalesce(c.n, 0),
           CASE WHEN f.status <> 'kept' THEN ARRAY(SELECT i FROM unnest(c.ids) AS i ORDER BY i) END
      FROM (VALUES (1, 'vertex', 'kept'), (2, 'vertex', 'removed'), (3, 'vertex', 'added'),
                   (4, 'cell', 'kept'), (5, 'cell', 'removed'), (6, 'cell', 'added')) AS f(o, element, status)
      LEFT JOIN c ON c.element = f.element AND c.status = f.status
     ORDER BY f.o
$$;

COMMENT ON FUNCTION tgsis.compare_geometry_versions(bigint, text, text, integer, integer) IS
    'what changed in a static geometry from one version (at a revision; NULL: its working revision) to another, without moving the session: six rows (vertex|cell, kept|removed|added) with the count and the ids (old ids removed, new ids added, ascending; NULL for kept)';
