-- tgsis.restore_shipped_row(): a restore's copy of a row the script ships replaces the shipped row.
-- On the extension route pg_dump dumps the catalog tables' rows
-- (final/config_dump.sql), and the CREATE EXTENSION of the restore has inserted
-- the rows the script ships (DEFAULT, its revision 0, the rights on DEFAULT
-- granted to tgsis_editor, the installation record) before those rows arrive.
-- The dumped rows must win: DEFAULT's working revision, set, owner and
-- validity, revision 0's name and visible set, the rights on DEFAULT as they
-- were (a revoked shipped right stays revoked) — so no dump filter, which
-- would keep the shipped state instead. DEFAULT and revision 0 take the dumped
-- values in place when their copies arrive (rows of the dump refer to them),
-- whatever order the tables come in; an installation row replaces the one of
-- its version. When DEFAULT arrives, the shipped rights on DEFAULT still there
-- (inserted by the CREATE EXTENSION transaction: the xmin of its pg_extension
-- row) go: the dump brings the rights DEFAULT really had, after versions
-- (pg_dump loads these tables in foreign-key order; a parallel pg_restore
-- does not, and fails on the foreign keys: docs/install.md). Only tgsis's
-- owner writes these tables (the others get their rows through its definer
-- functions, none of which inserts DEFAULT, revision 0 or an installation row
-- of a version installed already), so in normal use this never acts.
CREATE FUNCTION tgsis.restore_shipped_row()
RETURNS trigger
LANGUAGE plpgsql
VOLATILE
SET search_path = pg_catalog, pg_temp
AS $$
BEGIN
    IF TG_TABLE_NAME = 'versions' THEN
        IF NOT EXISTS (SELECT FROM tgsis.versions WHERE versionid = NEW.versionid) THEN
            RETURN NEW;
        END IF;
        DELETE FROM tgsis.version_privileges p
         WHERE p.versionid = NEW.versionid
           AND p.xmin = (SELECT e.xmin FROM pg_catalog.pg_extension e WHERE e.extname = 'tgsis');
        UPDATE tgsis.versions
           SET (name, parentid, initrevision, workingrevision, workingset, owner, description, created_at,
                valid_from, valid_to)
             = (NEW.name, NEW.parentid, NEW.initrevision, NEW.workingrevision, NEW.workingset, NEW.owner,
                NEW.description, NEW.created_at, NEW.valid_from, NEW.valid_to)
         WHERE versionid = NEW.versionid;
        RETURN NULL;
    ELSIF TG_TABLE_NAME = 'revisions' THEN
        UPDATE tgsis.revisions
           SET (versionid, name, created_at, created_by, saved_at, visibleset)
             = (NEW.versionid, NEW.name, NEW.created_at, NEW.created_by, NEW.saved_at, NEW.visibleset)
         WHERE revision = NEW.revision;
        IF FOUND THEN
            RETURN NULL;
        END IF;
    ELSE  -- installation
        DELETE FROM tgsis.installation WHERE version = NEW.version;
    END IF;
    RETURN NEW;
END
$$;

CREATE TRIGGER tgsis_restore_shipped_row BEFORE INSERT ON tgsis.versions
    FOR EACH ROW WHEN (NEW.versionid = 0) EXECUTE FUNCTION tgsis.restore_shipped_row();
CREATE TRIGGER tgsis_restore_shipped_row BEFORE INSERT ON tgsis.revisions
    FOR EACH ROW WHEN (NEW.revision = 0) EXECUTE FUNCTION tgsis.restore_shipped_row();
CREATE TRIGGER tgsis_restore_shipped_row BEFORE INSERT ON tgsis.installation
    FOR EACH ROW EXECUTE FUNCTION tgsis.restore_shipped_row();

REVOKE ALL ON FUNCTION tgsis.restore_shipped_row() FROM PUBLIC;

COMMENT ON FUNCTION tgsis.restore_shipped_row() IS
    'trigger on tgsis.versions (DEFAULT), revisions (0) and installation: a restored copy of a row the script ships replaces the row the restore''s CREATE EXTENSION inserted; DEFAULT''s arrival also drops the shipped rights on DEFAULT the dump does not bring back';
