-- tgsis.geometry_version_changes(geoid, old_version, new_version, old_revision, new_revision): tgsis.geometry_changes of one geometry between two versions or revisions.
-- Each side is the geometry as a version sees it at a revision (NULL: its
-- working revision), read without moving the session, as tgsis.rows_at
-- reads; needs model 1 versioned (tgsis.enable_feature_versioning). The
-- geometry must exist on both sides, as a static geometry of one geotype.
CREATE FUNCTION tgsis.geometry_version_changes(
    p_geoid        bigint,
    p_old_version  text,
    p_new_version  text,
    p_old_revision integer DEFAULT NULL,
    p_new_revision integer DEFAULT NULL)
RETURNS TABLE (element text, status text, old_id bigint, new_id bigint)
LANGUAGE sql
STABLE
AS $$
    SELECT *
      FROM tgsis.mesh_changes(p_geoid, tgsis.revision_set(tgsis.version_id(p_old_version), p_old_revision),
                              p_geoid, tgsis.revision_set(tgsis.version_id(p_new_version), p_new_revision),
                              format(' in version %L%s', p_old_version, ' at revision ' || p_old_revision),
                              format(' in version %L%s', p_new_version, ' at revision ' || p_new_revision))
$$;

COMMENT ON FUNCTION tgsis.geometry_version_changes(bigint, text, text, integer, integer) IS
    'every vertex and cell of a static geometry as one version (at a revision; NULL: its working revision) and as another sees it, without moving the session: element vertex|cell, status kept (old_id and new_id), removed (old_id) or added (new_id); needs model 1 versioned';
