-- tgsis.restore_shipped_row(): a restore's copy of a row the script ships replaces the shipped row.
-- On the extension route pg_dump dumps the catalog tables' rows
-- (core/config_dump.sql), and the CREATE EXTENSION of the restore has inserted
-- the rows the script ships (DEFAULT, its revision 0 and rights, the
-- installation record) before those rows arrive. The dumped rows must win:
-- DEFAULT's working revision, set, owner and validity, revision 0's saved
-- name and visible set, and the rights on DEFAULT as they were (a revoked
-- shipped right must stay revoked) — so no filter on the dump, which would
-- keep the shipped state instead. DEFAULT arriving while DEFAULT exists happens
-- only in a restore (versions is written by tgsis's definer functions alone,
-- and none inserts version 0): the shipped revision 0 and rights on DEFAULT
-- go (pg_dump loads revisions and version_privileges after versions, whose
-- key they reference) and DEFAULT takes the dumped values in place (its
-- children in the dump refer to it). An installation row for a version that
-- is recorded already replaces it.
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
        DELETE FROM tgsis.version_privileges WHERE versionid = NEW.versionid;
        DELETE FROM tgsis.revisions WHERE versionid = NEW.versionid;
        UPDATE tgsis.versions
           SET (name, parentid, initrevision, workingrevision, workingset, owner, description, created_at,
                valid_from, valid_to)
             = (NEW.name, NEW.parentid, NEW.initrevision, NEW.workingrevision, NEW.workingset, NEW.owner,
                NEW.description, NEW.created_at, NEW.valid_from, NEW.valid_to)
         WHERE versionid = NEW.versionid;
        RETURN NULL;
    END IF;
    -- tgsis.installation
    DELETE FROM tgsis.installation WHERE version = NEW.version;
    RETURN NEW;
END
$$;

CREATE TRIGGER tgsis_restore_shipped_row BEFORE INSERT ON tgsis.versions
    FOR EACH ROW WHEN (NEW.versionid = 0) EXECUTE FUNCTION tgsis.restore_shipped_row();
CREATE TRIGGER tgsis_restore_shipped_row BEFORE INSERT ON tgsis.installation
    FOR EACH ROW EXECUTE FUNCTION tgsis.restore_shipped_row();

REVOKE ALL ON FUNCTION tgsis.restore_shipped_row() FROM PUBLIC;

COMMENT ON FUNCTION tgsis.restore_shipped_row() IS
    'trigger on tgsis.versions (DEFAULT) and tgsis.installation: a restored copy of a shipped row replaces the row the restore''s CREATE EXTENSION inserted (DEFAULT keeps its key, its shipped revision 0 and rights make way for the dumped ones)';
