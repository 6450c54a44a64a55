-- tgsis.create_storage(): create the tables that hold the stored objects (models 1, 2 and 3) unless they exist.
-- Why a function and not CREATE TABLE statements in the script: on the
-- extension route everything the script creates is an extension member, which
-- pg_dump does not dump and which the CREATE EXTENSION of a restore creates
-- again as the script wrote it. These tables are the ones feature versioning
-- renames to <table>_ver and replaces by views (tgsis.enable_feature_versioning):
-- a restore would re-create the plain tables under the names of the dumped
-- views and lose the rows. Created by this function after CREATE EXTENSION
-- (tgsis.install does that), they are ordinary tables, dumped and restored with
-- their definitions, rows, sequences, grants and whatever versioning made of
-- them (docs/install.md, "Backup and restore"). The plain-SQL route calls it
-- from the script (core/storage.sql), so both routes leave the same objects.
-- The search path is the script's (tgsis, cube's schema): the tables use cube.
CREATE FUNCTION tgsis.create_storage()
RETURNS boolean
LANGUAGE plpgsql
VOLATILE
SET search_path FROM CURRENT
AS $storage$
BEGIN
    -- a view tgsis.geometry (feature versioning on) counts as existing storage
    IF to_regclass('tgsis.geometry') IS NOT NULL THEN
        RETURN false;
    END IF;

    PERFORM tgsis.create_model1_storage();   -- model1/storage.sql
    PERFORM tgsis.create_model2_storage();   -- model2/storage.sql
    PERFORM tgsis.create_model3_storage();   -- model3/storage.sql

    -- rights of the group roles on them (the other objects' are in core/grants.sql)
    GRANT SELECT ON tgsis.geometry, tgsis.vrtx, tgsis.point, tgsis.segment, tgsis.trgl, tgsis.tetra,
                    tgsis.atom, tgsis.part,
                    tgsis.times, tgsis.times_vrtx, tgsis.times_trgl,
                    tgsis.timem, tgsis.timet, tgsis.node, tgsis.d4dtrgl, tgsis.d4dvrtx
        TO tgsis_reader;
    GRANT INSERT, UPDATE, DELETE ON tgsis.geometry, tgsis.vrtx, tgsis.point, tgsis.segment, tgsis.trgl, tgsis.tetra,
                                    tgsis.atom, tgsis.part,
                                    tgsis.times, tgsis.times_vrtx, tgsis.times_trgl,
                                    tgsis.timem, tgsis.timet, tgsis.node, tgsis.d4dtrgl, tgsis.d4dvrtx
        TO tgsis_editor;
    GRANT USAGE ON SEQUENCE tgsis.geometry_geoid_seq TO tgsis_editor;
    -- class tables of feature classes refer to their geometry rows
    GRANT REFERENCES ON tgsis.geometry TO tgsis_admin;
    RETURN true;
END
$storage$;

REVOKE ALL ON FUNCTION tgsis.create_storage() FROM PUBLIC;

COMMENT ON FUNCTION tgsis.create_storage() IS
    'create the tables of stored objects (geometry, vrtx, point, segment, trgl, tetra, atom, part, times*, timem, timet, node, d4dtrgl, d4dvrtx) with their grants unless tgsis.geometry exists; returns whether it created them. Run by the plain-SQL script and by tgsis.install after CREATE EXTENSION, so that they are not extension members and pg_dump keeps them';
