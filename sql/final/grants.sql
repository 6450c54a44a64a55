-- Rights of the group roles on the objects of tgsis. Feature-class tables get
-- theirs from tgsis.register_feature_class.
GRANT USAGE ON SCHEMA tgsis TO tgsis_reader;
GRANT SELECT ON tgsis.error_codes, tgsis.installation, tgsis.property_types, tgsis.catalog TO tgsis_reader;
GRANT SELECT ON tgsis.class_tables TO tgsis_reader;
-- the registry of data models says only what tgsis is made of: anyone may read
-- it (the write path of every role consults it); only tgsis's owner writes it
GRANT SELECT ON tgsis.data_models, tgsis.model_tables TO PUBLIC;
-- (the storage tables get theirs from tgsis.create_storage)
-- versioning: readers see the version tree; editors create, save and delete
-- versions (per-version owner rights are enforced by the functions)
GRANT SELECT ON tgsis.versions, tgsis.revisions, tgsis.version_tree, tgsis.versioned_tables, tgsis.versioning_dropped,
                tgsis.conflicts, tgsis.version_privileges
    TO tgsis_reader;
-- the regions of conflicting meshes: read as the conflicts are, written only through
-- tgsis.record_conflict_regions and tgsis.resolve_region
GRANT SELECT ON tgsis.conflict_regions TO tgsis_reader;
-- the generated write triggers run as each table's owner and probe the locks
GRANT SELECT ON tgsis.object_locks TO PUBLIC;
-- version state changes only through the SECURITY DEFINER functions, which
-- check the caller's version rights (tgsis.has_version_privilege); the
-- helpers they share are theirs alone
REVOKE ALL ON FUNCTION tgsis.next_working_revision(integer, integer[], integer), tgsis.lock_for_merge(text, text),
                       tgsis.lock_version_pair(text, text),
                       tgsis.copy_object_state(text, text[], integer[], integer[], integer),
                       tgsis.update_shared_rows(tgsis.versioned_tables, text, text, text[], integer[], integer[], integer)
    FROM PUBLIC;
-- tgsis.catalog, versioned_tables and versioning_dropped are read-only too:
-- definer code acts on what they name (and EXECUTEs the recorded constraint
-- definitions), so only tgsis's definer functions write them, checking the
-- calling role and reading what they record from the system catalogs
GRANT EXECUTE ON FUNCTION tgsis.record_dropped(regclass, oid, boolean),
                          tgsis.register_versioned_table(regclass, text, text, integer, text, text, text, text[]),
                          tgsis.unregister_versioned_table(text, text), tgsis.forget_dropped(integer)
    TO tgsis_admin;
GRANT EXECUTE ON FUNCTION tgsis.enable_feature_versioning(), tgsis.disable_feature_versioning(boolean),
                          tgsis.compress_versions(boolean) TO tgsis_admin;
