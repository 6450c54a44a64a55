-- Rights of the group roles on the objects of tgsis. Feature-class tables get
-- theirs from tgsis.register_feature_class.
GRANT USAGE ON SCHEMA tgsis TO tgsis_reader;
GRANT SELECT ON tgsis.error_codes, tgsis.installation, tgsis.property_types, tgsis.catalog,
                tgsis.geometry, tgsis.vrtx, tgsis.point, tgsis.segment, tgsis.trgl, tgsis.tetra
    TO tgsis_reader;
GRANT INSERT, UPDATE, DELETE ON tgsis.geometry, tgsis.vrtx, tgsis.point, tgsis.segment, tgsis.trgl, tgsis.tetra
    TO tgsis_editor;
GRANT USAGE ON SEQUENCE tgsis.geometry_geoid_seq TO tgsis_editor;
GRANT INSERT, UPDATE, DELETE ON tgsis.catalog TO tgsis_admin;
-- versioning: readers see the version tree; editors create, save and delete
-- versions (per-version owner rights are enforced by the functions)
GRANT SELECT ON tgsis.versions, tgsis.revisions, tgsis.version_tree, tgsis.versioned_tables, tgsis.versioning_dropped,
                tgsis.conflicts
    TO tgsis_reader;
GRANT INSERT, UPDATE, DELETE ON tgsis.conflicts TO tgsis_editor;
GRANT INSERT, UPDATE, DELETE ON tgsis.versions, tgsis.revisions TO tgsis_editor;
GRANT USAGE ON SEQUENCE tgsis.revision_seq, tgsis.versions_versionid_seq TO tgsis_editor;
GRANT INSERT, UPDATE, DELETE ON tgsis.versioned_tables, tgsis.versioning_dropped TO tgsis_admin;
GRANT EXECUTE ON FUNCTION tgsis.enable_feature_versioning(), tgsis.disable_feature_versioning(boolean),
                          tgsis.compress_versions(boolean) TO tgsis_admin;
