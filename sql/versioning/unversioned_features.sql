-- tgsis.unversioned_features: the features of classes registered without versioning (one row per geoid).
-- Such a feature's rows in the storage every class shares (tgsis.geometry,
-- the vertex, simplex and model 2..5 tables) are rows of no version: they
-- carry revision 0, which every revision set holds, are changed in place and
-- deleted for good, so that every version and revision sees the one current
-- state (docs/versioning.md, "Versioning per class"). The writers of shared
-- storage (the views' INSTEAD OF triggers, the storage's statement check,
-- tgsis.close_object_rows) look their keys up here. Rows are added only by
-- tgsis.claim_unversioned_geoid, which hands out the geoid itself (nobody can
-- mark a geometry that exists, or another session's next one), and removed
-- with the class or by tgsis.forget_unversioned once no row of the geoid is
-- left.
CREATE TABLE tgsis.unversioned_features (
    geoid     bigint PRIMARY KEY,
    classname text   NOT NULL REFERENCES tgsis.catalog (classname) ON DELETE CASCADE
);

CREATE INDEX unversioned_features_classname_idx ON tgsis.unversioned_features (classname);

COMMENT ON TABLE tgsis.unversioned_features IS
    'geometries of features of classes without versioning (tgsis.catalog.versioned = false): their rows in versioned storage have revision 0, are seen by every version and revision, changed in place; written only by tgsis.claim_unversioned_geoid';
COMMENT ON COLUMN tgsis.unversioned_features.geoid IS 'the geometry (tgsis.geometry.geoid): a feature, or a member of a collection that is one';
COMMENT ON COLUMN tgsis.unversioned_features.classname IS 'its feature class (tgsis.catalog.classname)';

-- the generated write triggers of versioned views run as each table's owner and probe it
GRANT SELECT ON tgsis.unversioned_features TO PUBLIC;
