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
