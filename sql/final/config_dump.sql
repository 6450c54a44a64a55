-- On the extension route, mark the tables and sequences users fill as
-- configuration, so that pg_dump dumps their rows and values (it dumps no
-- member's rows otherwise) and a restore does not hand out a revision number
-- or a version id again. All rows are dumped, the shipped ones too: their
-- dumped state replaces the shipped state on restore (tgsis.restore_shipped_row).
-- The tables of stored objects are no members (tgsis.create_storage), nor is
-- anything versioning or feature classes create at run time: pg_dump dumps
-- those whole. error_codes and property_types are the script's own, never
-- changed. The plain-SQL route has no extension and needs none of this.
DO $do$
DECLARE
    v_name text;
BEGIN
    IF EXISTS (SELECT FROM pg_catalog.pg_extension WHERE extname = 'tgsis') THEN
        FOREACH v_name IN ARRAY ARRAY['tgsis.installation', 'tgsis.catalog', 'tgsis.versions', 'tgsis.revisions',
                                      'tgsis.version_privileges', 'tgsis.object_locks', 'tgsis.conflicts',
                                      'tgsis.conflict_regions',
                                      'tgsis.versioned_tables', 'tgsis.versioning_dropped', 'tgsis.unversioned_features',
                                      'tgsis.revision_objects',
                                      'tgsis.revision_seq', 'tgsis.versions_versionid_seq',
                                      'tgsis.versioning_dropped_id_seq'] LOOP
            PERFORM pg_catalog.pg_extension_config_dump(v_name::regclass, '');
        END LOOP;
    END IF;
END
$do$;
