-- tgsis.data_models, tgsis.model_tables: the registry of data models and of the tables that store them.
-- Why a registry: storage creation, grants, feature versioning, deletion, the
-- bounding box and the checks of a geometry all concern "every table of every
-- model" or "the tables of this geometry's model". They read these rows
-- instead of each typing the list, so a new data model is a new SQL folder
-- whose storage file registers its tables here (docs/developing.md).
-- The rows ship with the extension (each model's storage.sql inserts its
-- own); only tgsis's owner writes them: definer code acts on what they name.
CREATE TABLE tgsis.data_models (
    model           smallint PRIMARY KEY CHECK (model >= 0),
    name            text     NOT NULL UNIQUE,
    timemodel       text     UNIQUE CHECK (timemodel = upper(timemodel)),
    geotypes        text[]   NOT NULL DEFAULT '{}',
    timekey         jsonb    NOT NULL DEFAULT '[]' CHECK (jsonb_typeof(timekey) = 'array'),
    cell_levels     boolean  NOT NULL DEFAULT false,
    create_function text     NOT NULL,
    extent_function text,
    check_function  text,
    description     text     NOT NULL,
    merge_function  text,
    CONSTRAINT data_models_core CHECK ((model = 0) = (timemodel IS NULL)),
    CONSTRAINT data_models_hooks CHECK (model = 0 OR (extent_function IS NOT NULL AND check_function IS NOT NULL))
);

COMMENT ON TABLE tgsis.data_models IS
    'registry of the data models: one row per model (0: the geometry core every model shares); storage creation, grants, versioning, deletion, refresh and checks read it';
COMMENT ON COLUMN tgsis.data_models.model IS 'model number (0: geometry core, 1: static 3D objects, 2: surfaces at instants, 3: evolving surfaces, ...)';
COMMENT ON COLUMN tgsis.data_models.name IS 'short name of the model';
COMMENT ON COLUMN tgsis.data_models.timemodel IS
    'the value of tgsis.geometry.timemodel and tgsis.catalog.timemodel for geometries and classes of this model (NULL for the core)';
COMMENT ON COLUMN tgsis.data_models.geotypes IS 'the geotypes a geometry or feature class of this model may have';
COMMENT ON COLUMN tgsis.data_models.timekey IS
    'the time-key columns of the class tables of this model, between _geoid and the rest: [{"name": ..., "comment": ...}] in order; type double precision';
COMMENT ON COLUMN tgsis.data_models.cell_levels IS
    'whether its feature classes attach properties to the cells of a chosen level (tgsis.catalog.celllevel; G-maps) rather than to vertices or simplices';
COMMENT ON COLUMN tgsis.data_models.create_function IS 'function (schema tgsis, no arguments) that creates the model''s tables; called by tgsis.create_storage';
COMMENT ON COLUMN tgsis.data_models.extent_function IS
    'function (schema tgsis, geoid) returning (bbox cube, nvrtx bigint, ncell bigint) of a geometry of this model from its rows; read by tgsis.refresh_geometry';
COMMENT ON COLUMN tgsis.data_models.check_function IS
    'function (schema tgsis, geoid) returning (problem text, count bigint, example text) for a geometry of this model; read by tgsis.check_geometry';
COMMENT ON COLUMN tgsis.data_models.description IS 'what the model stores';
COMMENT ON COLUMN tgsis.data_models.merge_function IS
    'function (schema tgsis) (version text, action text, geoid bigint) returning bigint that merges a feature of this model changed on both sides slice by slice in SQL (the rows written; NULL: the merge refuses it); read by tgsis.merge_regions_in_sql. NULL: by region or as a whole object';

CREATE TABLE tgsis.model_tables (
    tablename   text     PRIMARY KEY,
    model       smallint NOT NULL REFERENCES tgsis.data_models,
    iudorder    smallint NOT NULL CHECK (iudorder >= 0),
    geotype     text,
    objectclass text     NOT NULL DEFAULT 'feature',
    keycolumn   text     NOT NULL DEFAULT 'geoid',
    geoidcolumn text     DEFAULT 'geoid',
    description text     NOT NULL,
    chunkcolumn text,
    chunkrefs   text[]   NOT NULL DEFAULT '{}',
    chunksize   integer,
    chunkdefault boolean NOT NULL DEFAULT false,
    -- rows deleted with their geometry are the geometry's: versioned by its id, in object class feature
    CONSTRAINT model_tables_per_geometry CHECK (geoidcolumn IS NULL OR (objectclass = 'feature' AND geoidcolumn = keycolumn)),
    -- a table stored in chunks (docs/storage.md, "Chunks and the mapping of ids") names its local-id column
    -- and a block size, a power of two; one stored as rows has neither, nor ref columns
    CONSTRAINT model_tables_chunks CHECK ((chunkcolumn IS NULL) = (chunksize IS NULL)
                                          AND (chunkcolumn IS NOT NULL OR chunkrefs = '{}')
                                          AND (chunksize IS NULL OR (chunksize >= 64 AND chunksize <= 16384
                                                                     AND chunksize & (chunksize - 1) = 0))),
    -- only a table registered for chunks is switched to them by default
    CONSTRAINT model_tables_chunkdefault CHECK (NOT chunkdefault OR chunkcolumn IS NOT NULL)
);

COMMENT ON TABLE tgsis.model_tables IS
    'registry of the storage tables (schema tgsis, keyed by geoid first) of each data model; created by the model''s create_function, granted, versioned and emptied through this list';
COMMENT ON COLUMN tgsis.model_tables.tablename IS 'table in schema tgsis (a versioned view over <table>_ver once feature versioning is on)';
COMMENT ON COLUMN tgsis.model_tables.model IS 'the data model (tgsis.data_models.model) whose geometries have rows here';
COMMENT ON COLUMN tgsis.model_tables.iudorder IS
    'order of the table among the feature tables when versioned (tgsis.versioned_tables.iudorder): referenced rows first, deleted last';
COMMENT ON COLUMN tgsis.model_tables.geotype IS 'only geometries of this geotype have rows here (e.g. trgl: SURFACE); NULL: every geometry of the model';
COMMENT ON COLUMN tgsis.model_tables.objectclass IS
    'the object class the table is versioned in (tgsis.versioned_tables.objectclass): feature for the rows of geometries, model for the sets of objects';
COMMENT ON COLUMN tgsis.model_tables.keycolumn IS 'the object key it is versioned by (geoid for the rows of geometries)';
COMMENT ON COLUMN tgsis.model_tables.geoidcolumn IS
    'the column holding geometry ids: the rows of a deleted geometry go with it (NULL: the table is not per geometry)';
COMMENT ON COLUMN tgsis.model_tables.description IS 'what a row is';
COMMENT ON COLUMN tgsis.model_tables.chunkcolumn IS
    'the local-id column the table is chunked by (tgsis.<table>_chunk, made by tgsis.create_chunk_table: blocks of chunksize consecutive ids of one object); NULL: stored as rows';
COMMENT ON COLUMN tgsis.model_tables.chunkrefs IS
    'the columns holding vertex ids, stored relative to the chunk''s smallest one (vbase) in its chunk table; empty for a table stored as rows';
COMMENT ON COLUMN tgsis.model_tables.chunksize IS
    'ids per chunk (a power of two, 64..16384: holes number slots as smallint; 1024 today); NULL when chunkcolumn is NULL';
COMMENT ON COLUMN tgsis.model_tables.chunkdefault IS
    'stored in chunks by default in a new database: switched by tgsis.create_storage unless tgsis.storage is rows (model 1''s tables, model 2''s time tables); the upgrade from 0.2.0 switches model 1''s only, an upgraded database keeps its time tables as rows; a table registered for chunks without it stays rows until tgsis.store_in_chunks (model 3''s, the G-maps'')';

-- the geometry core: one tgsis.geometry row per stored object of every model
INSERT INTO tgsis.data_models (model, name, timemodel, create_function, description)
VALUES (0, 'geometry core', NULL, 'create_geometry_storage',
        'the geometry rows every model shares (tgsis.geometry: geotype, time model, bbox, counts, meaning)');
INSERT INTO tgsis.model_tables (tablename, model, iudorder, objectclass, keycolumn, geoidcolumn, description) VALUES
    ('geometry',     0, 0, 'feature', 'geoid', 'geoid', 'one row per stored geometry (the feature id), of every model'),
    ('model_object', 0, 1, 'feature', 'geoid', 'geoid', 'a geometry''s membership of a model (a set of objects)'),
    ('model',        0, 0, 'model', 'modelid', NULL, 'a model: a named set of objects (tgsis.model_object)');
