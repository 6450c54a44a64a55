-- tgsis.create_storage(): create the tables of every registered data model (tgsis.data_models) that do not exist yet.
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
-- from the script (storage/storage.sql), so both routes leave the same objects.
-- The search path is the script's (tgsis, cube's schema): the tables use cube.
-- A model whose tables are all there is skipped, so the function also serves an
-- upgrade that registers a new model: its tables are created and granted, and
-- the geotype/time-model check of tgsis.geometry follows the registry.
-- The tables registered for chunks by default (tgsis.model_tables.chunkdefault: model 1's, model 2's time tables)
-- are switched to chunks right after they are created, empty, when
-- tgsis.chosen_storage() says chunks (the default; the setting tgsis.storage =
-- rows keeps rows): docs/storage.md, "The storage switch".
CREATE FUNCTION tgsis.create_storage()
RETURNS boolean
LANGUAGE plpgsql
VOLATILE
SET search_path FROM CURRENT
AS $storage$
DECLARE
    v_model   record;
    v_created boolean := false;
    v_core    boolean := to_regclass('tgsis.geometry') IS NULL;
    v_storage text := tgsis.chosen_storage();  -- TG001 for a bad tgsis.storage, before anything is made
BEGIN
    FOR v_model IN SELECT m.model, m.create_function FROM tgsis.data_models m ORDER BY m.model LOOP
        -- a versioned table's name is its view: it counts as existing storage
        CONTINUE WHEN NOT EXISTS (SELECT FROM tgsis.model_tables t
                                   WHERE t.model = v_model.model AND to_regclass(format('tgsis.%I', t.tablename)) IS NULL);
        IF EXISTS (SELECT FROM tgsis.model_tables t
                    WHERE t.model = v_model.model AND to_regclass(format('tgsis.%I', t.tablename)) IS NOT NULL) THEN
            RAISE EXCEPTION 'some tables of data model % exist and others do not', v_model.model
                USING ERRCODE = 'TG001',
                      DETAIL = (SELECT string_agg(format('tgsis.%I: %s', t.tablename,
                                                         CASE WHEN to_regclass(format('tgsis.%I', t.tablename)) IS NULL
                                                              THEN 'missing' ELSE 'exists' END), ', ' ORDER BY t.tablename)
                                  FROM tgsis.model_tables t WHERE t.model = v_model.model),
                      HINT = 'restore the missing tables from a backup, or drop the others, then run SELECT tgsis.create_storage()';
        END IF;
        EXECUTE format('SELECT tgsis.%I()', v_model.create_function);
        PERFORM tgsis.grant_model_tables(v_model.model);
        PERFORM tgsis.protect_model_tables(v_model.model);  -- per-class rights at the model tables
        IF v_storage = 'chunks' THEN  -- empty: the switch is cheap
            PERFORM tgsis.store_in_chunks(t.tablename)
               FROM tgsis.model_tables t
              WHERE t.model = v_model.model AND t.chunkdefault
              ORDER BY t.iudorder, t.tablename;
        END IF;
        v_created := true;
    END LOOP;
    IF v_created AND NOT v_core THEN
        -- a model added to existing storage: its geotypes become legal in tgsis.geometry
        EXECUTE format('ALTER TABLE %s DROP CONSTRAINT geometry_kind, ADD CONSTRAINT geometry_kind CHECK (%s)',
                       tgsis.storage_table('tgsis', 'geometry'), tgsis.geometry_kind_check());
    END IF;
    RETURN v_created;
END
$storage$;

REVOKE ALL ON FUNCTION tgsis.create_storage() FROM PUBLIC;

COMMENT ON FUNCTION tgsis.create_storage() IS
    'create the tables of every registered data model (tgsis.data_models, tgsis.model_tables) that are missing, with their grants, those registered for chunks by default (chunkdefault) stored in chunks unless the setting tgsis.storage is rows (tgsis.chosen_storage); returns whether it created any. Run by the plain-SQL script and by tgsis.install after CREATE EXTENSION, so that they are not extension members and pg_dump keeps them';
