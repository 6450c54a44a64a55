-- tgsis.grant_model_tables(model): the group roles' rights on a data model's storage tables.
-- Readers read them, editors write them (through the write path's checks);
-- the geometry core also hands out geometry ids and is referenced by the
-- feature-class tables of admins. From the registry, so that a new model's
-- tables get the same rights as the others without a list typed here.
CREATE FUNCTION tgsis.grant_model_tables(p_model smallint)
RETURNS void
LANGUAGE plpgsql
VOLATILE
AS $$
DECLARE
    v_table text;
BEGIN
    FOR v_table IN SELECT tablename FROM tgsis.model_tables WHERE model = p_model ORDER BY tablename LOOP
        EXECUTE format('GRANT SELECT ON tgsis.%I TO tgsis_reader', v_table);
        EXECUTE format('GRANT INSERT, UPDATE, DELETE ON tgsis.%I TO tgsis_editor', v_table);
    END LOOP;
    IF p_model = 0 THEN
        GRANT USAGE ON SEQUENCE tgsis.geometry_geoid_seq, tgsis.model_modelid_seq TO tgsis_editor;
        -- class tables of feature classes refer to their geometry rows
        GRANT REFERENCES ON tgsis.geometry TO tgsis_admin;
    END IF;
END
$$;

REVOKE ALL ON FUNCTION tgsis.grant_model_tables(smallint) FROM PUBLIC;

COMMENT ON FUNCTION tgsis.grant_model_tables(smallint) IS
    'grant SELECT to tgsis_reader and INSERT, UPDATE, DELETE to tgsis_editor on the storage tables of a data model (tgsis.model_tables); for the core also the geometry id sequence and REFERENCES on tgsis.geometry to tgsis_admin; called by tgsis.create_storage';
