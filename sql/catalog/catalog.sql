-- The catalog of feature classes: one row per class, written by
-- tgsis.register_feature_class and removed by tgsis.drop_feature_class.
CREATE TABLE tgsis.catalog (
    classname          text        PRIMARY KEY,
    schemaname         text        NOT NULL,
    geotype            text        NOT NULL,
    featuretable       text        NOT NULL,
    cellprotable       text        NOT NULL,
    otherprotable      text,
    viewname           text        NOT NULL,
    protablename       text,
    timemodel          text        NOT NULL DEFAULT 'STATIC' REFERENCES tgsis.data_models (timemodel),
    timeunit           text,
    proalignment       text        NOT NULL CHECK (proalignment IN ('VERTEX', 'CELL')),
    srs                integer     NOT NULL CHECK (srs >= 0),
    feature_properties jsonb       NOT NULL DEFAULT '[]',
    cell_properties    jsonb       NOT NULL DEFAULT '[]',
    instant_properties jsonb       NOT NULL DEFAULT '[]',
    description        text,
    created_at         timestamptz NOT NULL DEFAULT now(),
    created_by         name        NOT NULL DEFAULT current_user,
    celllevel          smallint    CHECK (celllevel >= 0),
    versioned          boolean     NOT NULL DEFAULT true,
    UNIQUE (schemaname, featuretable),
    UNIQUE (schemaname, cellprotable),
    UNIQUE (schemaname, otherprotable)
    -- (which geotypes and per-instant tables a time model has is the registry's,
    -- tgsis.data_models, checked by tgsis.register_feature_class, the only writer)
);

COMMENT ON TABLE tgsis.catalog IS 'feature classes: where their features and properties are stored and how';
COMMENT ON COLUMN tgsis.catalog.classname IS 'class name; also the name of its feature table';
COMMENT ON COLUMN tgsis.catalog.schemaname IS 'schema of the feature, cell-property and view tables';
COMMENT ON COLUMN tgsis.catalog.geotype IS 'geotype of every feature of the class';
COMMENT ON COLUMN tgsis.catalog.featuretable IS '<features>: one row per feature (_geoid = tgsis.geometry.geoid), one column per feature property';
COMMENT ON COLUMN tgsis.catalog.cellprotable IS '<features>_cellpros: (_geoid, _idx) and one column per vertex or cell property; temporal classes add _times (INSTANTS) or _timem, _timet (EVOLVING)';
COMMENT ON COLUMN tgsis.catalog.otherprotable IS
    '<features>_vertexpros (a CELL class) or <features>_simplexpros (a VERTEX class): (_geoid, _idx) and one column per property whose alignment is not proalignment (alignment is per property); NULL: the class has none';
COMMENT ON COLUMN tgsis.catalog.viewname IS '<features>_v: features joined with their geometry row, for psql users';
COMMENT ON COLUMN tgsis.catalog.protablename IS
    '<features>_pros: per-instant feature properties of temporal classes (_geoid, _times for INSTANTS; _geoid, _timem, _timet for EVOLVING); NULL for static classes';
COMMENT ON COLUMN tgsis.catalog.timemodel IS 'STATIC (model 1), INSTANTS (model 2: surfaces at instants) or EVOLVING (model 3: continuously evolving surfaces)';
COMMENT ON COLUMN tgsis.catalog.timeunit IS 'unit of model time for temporal classes (e.g. Ma, ages stored as negative numbers); larger is later';
COMMENT ON COLUMN tgsis.catalog.proalignment IS
    'alignment of the properties in cellprotable (VERTEX: _idx is a vrtxid; CELL: _idx is a pointid/segid/trglid/tetraid); a property with another "alignment" is in otherprotable';
COMMENT ON COLUMN tgsis.catalog.srs IS 'spatial reference id (EPSG code; 0 = undefined/local)';
COMMENT ON COLUMN tgsis.catalog.feature_properties IS 'per-feature properties in column order: [{"name": ..., "type": ...}]';
COMMENT ON COLUMN tgsis.catalog.cell_properties IS 'per-vertex or per-cell properties in column order: [{"name": ..., "type": ...}], with "size": k for a vector property (an array column of k values) and "alignment" for a property aligned otherwise than proalignment (in otherprotable)';
COMMENT ON COLUMN tgsis.catalog.instant_properties IS 'per-instant feature properties (columns of protablename) in column order: [{"name": ..., "type": ...}]';
COMMENT ON COLUMN tgsis.catalog.description IS 'free text';
COMMENT ON COLUMN tgsis.catalog.created_at IS 'when the class was registered';
COMMENT ON COLUMN tgsis.catalog.created_by IS 'role that registered it';
COMMENT ON COLUMN tgsis.catalog.celllevel IS
    'classes of a model with cell levels (tgsis.data_models.cell_levels: G-maps): the dimension i of the cells their properties belong to (_idx = abstract cell id); NULL for the others';
COMMENT ON COLUMN tgsis.catalog.versioned IS
    'true: the class is versioned with every class while feature versioning is on (tgsis.enable_feature_versioning); false: registered without versioning: its tables stay plain, its features'' rows in the shared storage are of no version (tgsis.unversioned_features), one state that every version sees, written in DEFAULT only';
