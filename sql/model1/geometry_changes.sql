-- tgsis.geometry_changes(old, new): one row per vertex and cell of two stored geometries: kept (with both ids), removed (old id) or added (new id).
-- Both are read as the session sees them (its version), must exist and be
-- static geometries of one geotype other than GEOMETRYCOLLECTION. The
-- definitions are those of tgsis.mesh_changes (and of tgsis.compare_meshes
-- in the Python client); tgsis.compare_geometries counts the same rows.
-- The kept vertices are the vertex matches: old_id and new_id of each pair.
CREATE FUNCTION tgsis.geometry_changes(p_old bigint, p_new bigint)
RETURNS TABLE (element text, status text, old_id bigint, new_id bigint)
LANGUAGE sql
STABLE
AS $$
    SELECT * FROM tgsis.mesh_changes(p_old, NULL, p_new, NULL)
$$;

COMMENT ON FUNCTION tgsis.geometry_changes(bigint, bigint) IS
    'every vertex and cell (point, segment, triangle, tetrahedron) of two static geometries of one geotype, in the session''s version: element vertex|cell, status kept (old_id and new_id), removed (old_id) or added (new_id); vertices are kept by equal coordinates, cells by kept vertices in the same orientation';
