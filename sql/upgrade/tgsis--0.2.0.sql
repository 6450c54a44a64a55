-- tgsis 0.2.0: built from sql/sources.txt, do not edit
\echo Use "CREATE EXTENSION tgsis" to load this file. \quit

-- ==== core/schema.sql ====
-- The tgsis schema holds every object of the extension.
-- CREATE EXTENSION creates it from the control file's `schema` (and does not
-- make it an extension member, so CREATE SCHEMA IF NOT EXISTS would be refused
-- in this script); the plain-SQL install (tgsis.install) must create it here.
DO $do$
BEGIN
    IF to_regnamespace('tgsis') IS NULL THEN
        CREATE SCHEMA tgsis;
    END IF;
END
$do$;

COMMENT ON SCHEMA tgsis IS
    'tgsis: spatio-temporal geoscience information system (geological objects with topology, properties, time and versions)';

-- ==== core/roles.sql ====
-- Group roles of tgsis, each one a member of the one before:
--   tgsis_reader  reads features, versions and history;
--   tgsis_editor  also writes features and works in versions;
--   tgsis_admin   also registers feature classes and merges into DEFAULT.
-- Roles belong to the cluster, not to a database: they are created only when
-- missing and outlive DROP EXTENSION. Without CREATEROLE the install fails
-- with TG002 and tells the DBA what to run, rather than half-installing.
DO $do$
DECLARE
    v_roles   CONSTANT text[] := ARRAY['tgsis_reader', 'tgsis_editor', 'tgsis_admin'];
    v_comment CONSTANT text[] := ARRAY[
        'tgsis group role: read features, versions and their history',
        'tgsis group role: tgsis_reader plus writing features and working in versions',
        'tgsis group role: tgsis_editor plus registering feature classes and merging into DEFAULT'];
    v_missing text[];
    v_i       int;
BEGIN
    SELECT coalesce(array_agg(r ORDER BY ord), '{}')
      INTO v_missing
      FROM unnest(v_roles) WITH ORDINALITY AS u(r, ord)
     WHERE NOT EXISTS (SELECT FROM pg_catalog.pg_roles WHERE rolname = u.r);

    IF cardinality(v_missing) > 0
       AND NOT (SELECT rolsuper OR rolcreaterole FROM pg_catalog.pg_roles WHERE rolname = current_user) THEN
        -- everything the DBA must run once, tgsis_nobody too (core/nobody_role.sql, versioning/storage_hop.sql)
        RAISE EXCEPTION 'tgsis needs the group roles %, and role % may not create roles',
                array_to_string(v_missing, ', '), current_user
            USING ERRCODE = 'TG002',
                  DETAIL = 'Roles are shared by all databases of the cluster; creating them needs CREATEROLE.',
                  HINT = format('Ask a DBA to run once: %s GRANT tgsis_reader TO tgsis_editor; GRANT tgsis_editor TO tgsis_admin;%s',
                                (SELECT string_agg(format('CREATE ROLE %I NOLOGIN;', r), ' ') FROM unnest(v_missing) AS r),
                                CASE WHEN NOT EXISTS (SELECT FROM pg_catalog.pg_roles WHERE rolname = 'tgsis_nobody')
                                     THEN format(' CREATE ROLE tgsis_nobody NOLOGIN NOINHERIT; GRANT tgsis_nobody TO %I;', current_user)
                                     WHEN NOT pg_catalog.pg_has_role(current_user, 'tgsis_nobody', 'MEMBER')
                                     THEN format(' GRANT tgsis_nobody TO %I;', current_user)
                                     ELSE '' END);
    END IF;

    FOR v_i IN 1 .. cardinality(v_roles) LOOP
        IF v_roles[v_i] = ANY (v_missing) THEN
            EXECUTE format('CREATE ROLE %I NOLOGIN', v_roles[v_i]);
            EXECUTE format('COMMENT ON ROLE %I IS %L', v_roles[v_i], v_comment[v_i]);
        END IF;
        -- editor is a reader, admin is an editor
        IF v_i > 1 AND NOT pg_catalog.pg_has_role(v_roles[v_i], v_roles[v_i - 1], 'MEMBER') THEN
            EXECUTE format('GRANT %I TO %I', v_roles[v_i - 1], v_roles[v_i]);
        END IF;
    END LOOP;
END
$do$;

-- ==== core/nobody_role.sql ====
-- The role tgsis_nobody: no rights of its own, and a member of no role.
-- tgsis's definer code runs as tgsis's owner; when it acts on a table
-- another role owns, it calls that table's runner (<table>_ver_run(),
-- SECURITY DEFINER, owned by the table's owner) from tgsis.storage_hop,
-- which runs as this role. Had the table's owner made its runner SECURITY
-- INVOKER, the runner's code would run as tgsis_nobody, which can do
-- nothing, instead of as tgsis's owner (docs/security.md). Like the group
-- roles, it belongs to the cluster and is created only when missing.
DO $do$
BEGIN
    IF NOT EXISTS (SELECT FROM pg_catalog.pg_roles WHERE rolname = 'tgsis_nobody') THEN
        IF NOT (SELECT rolsuper OR rolcreaterole FROM pg_catalog.pg_roles WHERE rolname = current_user) THEN
            RAISE EXCEPTION 'tgsis needs the role tgsis_nobody, and role % may not create roles', current_user
                USING ERRCODE = 'TG002',
                      DETAIL = 'Roles are shared by all databases of the cluster; creating them needs CREATEROLE.',
                      HINT = format('Ask a DBA to run once: CREATE ROLE tgsis_nobody NOLOGIN NOINHERIT; GRANT tgsis_nobody TO %I;',
                                    current_user);
        END IF;
        CREATE ROLE tgsis_nobody NOLOGIN NOINHERIT;
        COMMENT ON ROLE tgsis_nobody IS
            'tgsis: a role with no rights, as which tgsis calls the runners of tables other roles own (tgsis.storage_hop)';
    END IF;
END
$do$;

-- ==== core/error_codes.sql ====
-- The SQLSTATEs tgsis raises. Class TG is ours (SQL reserves classes starting
-- with I-Z for implementations; PostgreSQL uses none of them). The second
-- character of the subclass says the area, see docs/errors.md. The Python
-- client maps each row to an exception class (tgsis.errors); a test keeps
-- this table, the Python classes and docs/errors.md in step.
CREATE TABLE tgsis.error_codes (
    sqlstate    char(5) PRIMARY KEY CHECK (sqlstate ~ '^TG[0-9A-Z]{3}$'),
    name        text    NOT NULL UNIQUE CHECK (name ~ '^[a-z][a-z0-9_]*$'),
    area        text    NOT NULL CHECK (area IN ('core', 'input', 'catalog', 'versioning', 'time', 'mesh')),
    description text    NOT NULL
);

COMMENT ON TABLE tgsis.error_codes IS
    'SQLSTATEs raised by tgsis (class TG); the Python client maps each to an exception class';
COMMENT ON COLUMN tgsis.error_codes.sqlstate IS 'five-character SQLSTATE, always TGxxx';
COMMENT ON COLUMN tgsis.error_codes.name IS 'condition name; the Python class is its CamelCase form plus "Error"';
COMMENT ON COLUMN tgsis.error_codes.area IS 'part of tgsis that raises it: core, input, catalog, versioning, time or mesh';
COMMENT ON COLUMN tgsis.error_codes.description IS 'when the error is raised';

INSERT INTO tgsis.error_codes (sqlstate, name, area, description) VALUES
    ('TG000', 'tgsis',            'core',    'a tgsis error that fits no narrower code'),
    ('TG001', 'installation',     'core',    'the tgsis objects in the database cannot be installed, upgraded or used at this version'),
    ('TG002', 'missing_privilege','core',    'the current role lacks a right tgsis needs (creating roles, owning a version, merging into DEFAULT)'),
    ('TG100', 'invalid_input',    'input',   'an argument is out of range, NULL where a value is required, or otherwise malformed'),
    ('TG101', 'invalid_name',     'input',   'a name (feature class, property, version, table) is empty, too long, or would need quoting where that is not allowed'),
    ('TG102', 'invalid_geometry', 'input',   'coordinates are NaN or infinite, or a simplex has out-of-range or repeated vertex indices'),
    ('TG103', 'invalid_property', 'input',   'a property has an unknown name, a type outside the allowed list, or the wrong number of values'),
    ('TG104', 'invalid_g_map',    'input',   'arrays that are no valid n-G-map (an alpha_i that is not an involution, a fixed point below alpha_n, alpha_i o alpha_j not an involution for i + 2 <= j, a dart whose alpha_i lies in another topology period), or a G-map an operation cannot take; reserved for models 4 and 5'),
    ('TG200', 'not_found',        'catalog', 'a named object (feature class, feature, geometry, table) does not exist'),
    ('TG201', 'already_exists',   'catalog', 'an object with that name or key exists already'),
    ('TG202', 'in_use',           'catalog', 'an object cannot be dropped or changed while others depend on it'),
    ('TG300', 'versioning',       'versioning', 'a versioning error that fits no narrower code'),
    ('TG301', 'read_only_revision', 'versioning', 'a write while the session views an older revision, or into a frozen (saved) revision'),
    ('TG302', 'unsolved_conflicts', 'versioning', 'a merge or refresh while objects changed on both sides have no recorded solution'),
    ('TG303', 'object_locked',    'versioning', 'a write (or merge) would change an object another version, or another role, holds a lock on'),
    ('TG304', 'checkout_conflict', 'versioning', 'a check-in of an object that another writer changed (or deleted) since it was checked out'),
    ('TG305', 'not_versioned',    'versioning', 'a write in a version other than DEFAULT (or at an older revision) to tables that are not versioned: it would land in DEFAULT');

-- ==== core/installation.sql ====
-- Which tgsis versions were installed in this database, and how. The plain-SQL
-- route (tgsis.install) reads the newest row to decide between a no-op and an
-- upgrade; the extension route has pg_extension for that and writes here too.
CREATE TABLE tgsis.installation (
    version      text        PRIMARY KEY,
    method       text        NOT NULL CHECK (method IN ('extension', 'sql')),
    installed_at timestamptz NOT NULL DEFAULT now(),
    installed_by name        NOT NULL DEFAULT current_user
);

COMMENT ON TABLE tgsis.installation IS
    'history of the tgsis versions installed or upgraded to in this database (newest installed_at is current)';
COMMENT ON COLUMN tgsis.installation.version IS 'tgsis version whose script ran';
COMMENT ON COLUMN tgsis.installation.method IS
    'extension: CREATE/ALTER EXTENSION; sql: the same script run by tgsis.install() where extension files cannot be installed';
COMMENT ON COLUMN tgsis.installation.installed_at IS 'when the script ran (transaction start)';
COMMENT ON COLUMN tgsis.installation.installed_by IS 'role that ran it';

-- While CREATE EXTENSION runs its script, pg_extension already has the row.
INSERT INTO tgsis.installation (version, method)
VALUES ('0.2.0',
        CASE WHEN EXISTS (SELECT FROM pg_catalog.pg_extension WHERE extname = 'tgsis')
             THEN 'extension' ELSE 'sql' END);

-- ==== core/version.sql ====
-- tgsis.version(): the version of the tgsis objects installed in this database.
CREATE FUNCTION tgsis.version()
RETURNS text
LANGUAGE sql
IMMUTABLE
PARALLEL SAFE
AS $$ SELECT '0.2.0'::text $$;

COMMENT ON FUNCTION tgsis.version() IS
    'version of the tgsis SQL objects installed in this database (the same as the Python client''s tgsis.__version__ when they match)';

-- ==== core/or_list.sql ====
-- tgsis.or_list(words): 'A, B or C' — a list of choices for a message, from the rows that define them.
-- Messages that list what is allowed (geotypes, time models) build the list
-- from the registry, so they stay right when a data model is added.
CREATE FUNCTION tgsis.or_list(p_words text[])
RETURNS text
LANGUAGE sql
IMMUTABLE
PARALLEL SAFE
AS $$
    SELECT CASE WHEN cardinality(p_words) IS NULL OR cardinality(p_words) = 0 THEN ''
                WHEN cardinality(p_words) = 1 THEN p_words[1]
                ELSE array_to_string(p_words[1:cardinality(p_words) - 1], ', ') || ' or ' || p_words[cardinality(p_words)]
           END
$$;

COMMENT ON FUNCTION tgsis.or_list(text[]) IS 'the words as a list of choices for a message: ''A, B or C'' ('''' for none)';

-- ==== geometry/data_models.sql ====
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

CREATE TABLE tgsis.model_tables (
    tablename   text     PRIMARY KEY,
    model       smallint NOT NULL REFERENCES tgsis.data_models,
    iudorder    smallint NOT NULL CHECK (iudorder >= 0),
    geotype     text,
    objectclass text     NOT NULL DEFAULT 'feature',
    keycolumn   text     NOT NULL DEFAULT 'geoid',
    geoidcolumn text     DEFAULT 'geoid',
    description text     NOT NULL,
    -- rows deleted with their geometry are the geometry's: versioned by its id, in object class feature
    CONSTRAINT model_tables_per_geometry CHECK (geoidcolumn IS NULL OR (objectclass = 'feature' AND geoidcolumn = keycolumn))
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

-- the geometry core: one tgsis.geometry row per stored object of every model
INSERT INTO tgsis.data_models (model, name, timemodel, create_function, description)
VALUES (0, 'geometry core', NULL, 'create_geometry_storage',
        'the geometry rows every model shares (tgsis.geometry: geotype, time model, bbox, counts, meaning)');
INSERT INTO tgsis.model_tables (tablename, model, iudorder, objectclass, keycolumn, geoidcolumn, description) VALUES
    ('geometry',     0, 0, 'feature', 'geoid', 'geoid', 'one row per stored geometry (the feature id), of every model'),
    ('model_object', 0, 1, 'feature', 'geoid', 'geoid', 'a geometry''s membership of a model (a set of objects)'),
    ('model',        0, 0, 'model', 'modelid', NULL, 'a model: a named set of objects (tgsis.model_object)');

-- ==== geometry/geometry_kind_check.sql ====
-- tgsis.geometry_kind_check(): the CHECK expression of tgsis.geometry's (geotype, timemodel) pairs, from the registry.
-- Each data model says which geotypes its geometries have; a CHECK built
-- from the rows (not typed in the table) follows the registry when a model
-- is added (tgsis.create_storage re-creates the constraint then). Not a
-- foreign key: every geometry insert would lock a registry row.
CREATE FUNCTION tgsis.geometry_kind_check()
RETURNS text
LANGUAGE sql
STABLE
AS $$
    SELECT string_agg(format('(timemodel = %L AND geotype = ANY (%L::text[]))', m.timemodel, m.geotypes), ' OR '
                      ORDER BY m.model)
      FROM tgsis.data_models m
     WHERE m.model > 0
$$;

COMMENT ON FUNCTION tgsis.geometry_kind_check() IS
    'CHECK expression (text) allowing exactly the (timemodel, geotype) pairs of the registered data models (tgsis.data_models); used for the constraint geometry_kind of tgsis.geometry';

-- ==== geometry/storage.sql ====
-- tgsis.create_geometry_storage(): create tgsis.geometry, the geometry core every data model shares.
-- One row per stored object whatever its model: its geotype and time model
-- (which model's tables hold the rest, tgsis.data_models), bounding box,
-- counts and what the file meant. Called by tgsis.create_storage (core/create_storage.sql
-- says why the tables are created by a function after CREATE EXTENSION).
-- The search path is the script's (tgsis, cube's schema).
CREATE FUNCTION tgsis.create_geometry_storage()
RETURNS void
LANGUAGE plpgsql
VOLATILE
SET search_path FROM CURRENT
AS $storage$
BEGIN
    -- ---- tgsis.geometry
    -- One row per stored geometry of model 1 (static 3D objects). Its vertices and
    -- simplices live in vrtx/point/segment/trgl/tetra under the same geoid.
    -- A GEOMETRYCOLLECTION lists its members in geoids; the members the client
    -- stored with it are owned by it (collection = its geoid) and are deleted
    -- with it, while geometries merely listed (e.g. other features) are not.
    CREATE TABLE tgsis.geometry (
        geoid      bigint GENERATED BY DEFAULT AS IDENTITY PRIMARY KEY,
        geotype    text   NOT NULL,
        geoname    text,
        geoids     bigint[],
        collection bigint REFERENCES tgsis.geometry (geoid),
        bbox       cube,
        nvrtx      bigint NOT NULL DEFAULT 0 CHECK (nvrtx >= 0),
        ncell      bigint NOT NULL DEFAULT 0 CHECK (ncell >= 0),
        timemodel  text   NOT NULL DEFAULT 'STATIC',
        alive      boolean NOT NULL DEFAULT false,
        colorred   real   CHECK (colorred BETWEEN 0 AND 1),
        colorgreen real   CHECK (colorgreen BETWEEN 0 AND 1),
        colorblue  real   CHECK (colorblue BETWEEN 0 AND 1),
        zpositive  text   CHECK (zpositive IN ('Elevation', 'Depth')),
        crs        jsonb  CHECK (jsonb_typeof(crs) = 'array'),
        metadata   jsonb  CHECK (jsonb_typeof(metadata) = 'object'),
        created_at timestamptz NOT NULL DEFAULT now(),
        CONSTRAINT geometry_collection_members CHECK ((geotype = 'GEOMETRYCOLLECTION') = (geoids IS NOT NULL)),
        CONSTRAINT geometry_bbox_is_3d CHECK (bbox IS NULL OR cube_dim(bbox) = 3),
        CONSTRAINT geometry_members_do_not_nest CHECK (collection IS NULL OR geotype <> 'GEOMETRYCOLLECTION')
    );

    -- which geotypes each time model has: from the registry (tgsis.geometry_kind_check)
    EXECUTE format('ALTER TABLE tgsis.geometry ADD CONSTRAINT geometry_kind CHECK (%s)', tgsis.geometry_kind_check());

    CREATE INDEX geometry_bbox_idx ON tgsis.geometry USING gist (bbox);
    -- finds the members of a collection (delete_geometry, and the foreign-key check when a collection is deleted)
    CREATE INDEX geometry_collection_idx ON tgsis.geometry (collection) WHERE collection IS NOT NULL;

    COMMENT ON SEQUENCE tgsis.geometry_geoid_seq IS 'geometry ids (identity of tgsis.geometry)';
    COMMENT ON TABLE tgsis.geometry IS
        'model 1: one row per geometry (indexed face set); vertices and simplices are in tgsis.vrtx, point, segment, trgl, tetra';
    COMMENT ON COLUMN tgsis.geometry.geoid IS 'geometry id; also the feature id (_geoid) in feature tables';
    COMMENT ON COLUMN tgsis.geometry.geotype IS
        'MULTIPOINT, MULTILINESTRING, SURFACE, MULTITETRA or GEOMETRYCOLLECTION (the geotypes of its time model: tgsis.data_models.geotypes)';
    COMMENT ON COLUMN tgsis.geometry.geoname IS 'name of the object (e.g. from a GOCAD header)';
    COMMENT ON COLUMN tgsis.geometry.geoids IS 'members of a GEOMETRYCOLLECTION in order (NULL for the other geotypes)';
    COMMENT ON COLUMN tgsis.geometry.collection IS
        'the GEOMETRYCOLLECTION that owns this geometry (deleted with it by tgsis.delete_geometry); NULL for geometries of their own';
    COMMENT ON COLUMN tgsis.geometry.bbox IS
        '3D bounding box (cube) of the vertices (of a temporal geometry: of all its instants), kept by the write path (tgsis.refresh_geometry after raw SQL edits); GiST-indexed';
    COMMENT ON COLUMN tgsis.geometry.nvrtx IS 'number of vertices (temporal: vertex rows of model 2, nodes of model 3), kept by the write path';
    COMMENT ON COLUMN tgsis.geometry.ncell IS 'number of simplices (points, segments, triangles or tetrahedra; temporal: of all instants or periods), kept by the write path';
    COMMENT ON COLUMN tgsis.geometry.timemodel IS
        'its data model (tgsis.data_models.timemodel): STATIC (model 1: tgsis.vrtx and simplices), INSTANTS (model 2: a surface at instants, tgsis.times*) or EVOLVING (model 3: tgsis.timem, timet, node, d4dtrgl, d4dvrtx)';
    COMMENT ON COLUMN tgsis.geometry.alive IS
        'temporal geometries: whether the object still exists after its last instant (it keeps its last shape); ignored for STATIC';
    COMMENT ON COLUMN tgsis.geometry.colorred IS 'display colour, red component in [0, 1] (NULL: none)';
    COMMENT ON COLUMN tgsis.geometry.colorgreen IS 'display colour, green component in [0, 1]';
    COMMENT ON COLUMN tgsis.geometry.colorblue IS 'display colour, blue component in [0, 1]';
    COMMENT ON COLUMN tgsis.geometry.zpositive IS
        'z convention of the file the geometry came from: Elevation (up positive) or Depth (down positive); NULL: not stated. Stored z (tgsis.vrtx.z, bbox) is always elevation: the write path negates the z of a Depth geometry, the read path negates it back';
    COMMENT ON COLUMN tgsis.geometry.crs IS
        'the coordinate-system block of the file (GOCAD_ORIGINAL_COORDINATE_SYSTEM: NAME, AXIS_NAME, AXIS_UNIT, ZPOSITIVE, ...), its lines in order; NULL: none';
    COMMENT ON COLUMN tgsis.geometry.metadata IS
        'other facts the file format kept for a faithful round trip (GOCAD header lines, property names, sizes, kinds, units and classes as written, ...): the mesh metadata without colour, z convention, coordinate system and atoms, which have columns or tables of their own';
    COMMENT ON COLUMN tgsis.geometry.created_at IS 'when the geometry was stored';

    -- ---- tgsis.model, tgsis.model_object
    -- Models as sets of objects (a mine's resource model, a geotechnical
    -- model, ...): an object may belong to several models and a model's
    -- objects change from version to version like the objects themselves.
    -- The membership is part of the object (versioned with it, deleted with
    -- it); the model's own row is an object of class 'model'.
    CREATE TABLE tgsis.model (
        modelid     bigint GENERATED BY DEFAULT AS IDENTITY PRIMARY KEY,
        name        text   NOT NULL CHECK (name <> ''),
        description text,
        created_at  timestamptz NOT NULL DEFAULT now()
    );
    CREATE TABLE tgsis.model_object (
        geoid   bigint NOT NULL,
        modelid bigint NOT NULL,
        PRIMARY KEY (geoid, modelid)
    );
    -- the objects of a model
    CREATE INDEX model_object_model_idx ON tgsis.model_object (modelid);

    COMMENT ON SEQUENCE tgsis.model_modelid_seq IS 'model ids (identity of tgsis.model)';
    COMMENT ON TABLE tgsis.model IS 'models: named sets of objects (their members are in tgsis.model_object), versioned as object class model';
    COMMENT ON COLUMN tgsis.model.modelid IS 'model id';
    COMMENT ON COLUMN tgsis.model.name IS 'the model''s name (unique in each version: tgsis.create_model checks)';
    COMMENT ON COLUMN tgsis.model.description IS 'what the model is, for people';
    COMMENT ON COLUMN tgsis.model.created_at IS 'when the model was created';
    COMMENT ON TABLE tgsis.model_object IS
        'the objects of each model: one row per object and model it belongs to (versioned with the object, deleted with it)';
    COMMENT ON COLUMN tgsis.model_object.geoid IS 'the object (tgsis.geometry.geoid: a feature)';
    COMMENT ON COLUMN tgsis.model_object.modelid IS 'the model (tgsis.model.modelid)';
END
$storage$;

REVOKE ALL ON FUNCTION tgsis.create_geometry_storage() FROM PUBLIC;

COMMENT ON FUNCTION tgsis.create_geometry_storage() IS
    'create tgsis.geometry (the geometry core of every data model) with the geotype and time-model check the registry gives, and the sets of objects (tgsis.model, tgsis.model_object); called once by tgsis.create_storage';

-- ==== geometry/grant_model_tables.sql ====
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

-- ==== model1/storage.sql ====
-- tgsis.create_model1_storage(): create the tables of model 1 (static 3D objects: vertices, simplices, atoms, parts) and register them.
-- Their geometry rows are the core's (geometry/storage.sql).
-- Called by tgsis.create_storage (core/create_storage.sql says why the tables
-- are created by a function after CREATE EXTENSION, not by the script).
-- The search path is the script's (tgsis, cube's schema).
CREATE FUNCTION tgsis.create_model1_storage()
RETURNS void
LANGUAGE plpgsql
VOLATILE
SET search_path FROM CURRENT
AS $storage$
BEGIN
    -- ---- tgsis.vrtx
    -- Vertices of model-1 geometries. Key (geoid, vrtxid): vertex ids are local to
    -- their geometry (0..n-1 when uploaded), so simplices point at (geoid, vrtxid).
    -- No foreign key to tgsis.geometry: a per-row check would make bulk upload
    -- several times slower (measured, docs/performance.md); the write path keeps
    -- references right and tgsis.check_geometry() verifies them.
    CREATE TABLE tgsis.vrtx (
        geoid  bigint           NOT NULL,
        vrtxid bigint           NOT NULL,
        x      double precision NOT NULL,
        y      double precision NOT NULL,
        z      double precision NOT NULL,
        PRIMARY KEY (geoid, vrtxid)
    );

    COMMENT ON TABLE tgsis.vrtx IS 'model 1: vertices of geometries, keyed by (geoid, vrtxid)';
    COMMENT ON COLUMN tgsis.vrtx.geoid IS 'geometry (tgsis.geometry.geoid)';
    COMMENT ON COLUMN tgsis.vrtx.vrtxid IS 'vertex id, local to the geometry';
    COMMENT ON COLUMN tgsis.vrtx.x IS 'x coordinate (unit of the class''s SRS)';
    COMMENT ON COLUMN tgsis.vrtx.y IS 'y coordinate';
    COMMENT ON COLUMN tgsis.vrtx.z IS 'z coordinate (up positive)';

    -- ---- tgsis.point
    -- Points of MULTIPOINT geometries: each row points at 1 vertex id(s) of the same geometry.
    -- Same keying and the same reason for no foreign keys as tgsis.vrtx.
    CREATE TABLE tgsis.point (
        geoid  bigint NOT NULL,
        pointid bigint NOT NULL,
        vrtxid1 bigint NOT NULL,
        PRIMARY KEY (geoid, pointid)
    );

    COMMENT ON TABLE tgsis.point IS 'model 1: points of MULTIPOINT geometries, keyed by (geoid, pointid)';
    COMMENT ON COLUMN tgsis.point.geoid IS 'geometry (tgsis.geometry.geoid)';
    COMMENT ON COLUMN tgsis.point.pointid IS 'simplex id, local to the geometry; _idx of CELL-aligned properties';
    COMMENT ON COLUMN tgsis.point.vrtxid1 IS 'vertex 1 (tgsis.vrtx.vrtxid of the same geoid)';

    -- ---- tgsis.segment
    -- Segments of MULTILINESTRING geometries: each row points at 2 vertex id(s) of the same geometry.
    -- Same keying and the same reason for no foreign keys as tgsis.vrtx.
    CREATE TABLE tgsis.segment (
        geoid  bigint NOT NULL,
        segid bigint NOT NULL,
        vrtxid1 bigint NOT NULL,
        vrtxid2 bigint NOT NULL,
        CONSTRAINT segment_distinct_vertices CHECK (vrtxid1 <> vrtxid2),
        PRIMARY KEY (geoid, segid)
    );

    COMMENT ON TABLE tgsis.segment IS 'model 1: segments of MULTILINESTRING geometries, keyed by (geoid, segid)';
    COMMENT ON COLUMN tgsis.segment.geoid IS 'geometry (tgsis.geometry.geoid)';
    COMMENT ON COLUMN tgsis.segment.segid IS 'simplex id, local to the geometry; _idx of CELL-aligned properties';
    COMMENT ON COLUMN tgsis.segment.vrtxid1 IS 'vertex 1 (tgsis.vrtx.vrtxid of the same geoid)';
    COMMENT ON COLUMN tgsis.segment.vrtxid2 IS 'vertex 2 (tgsis.vrtx.vrtxid of the same geoid)';

    -- ---- tgsis.trgl
    -- Triangles of SURFACE geometries: each row points at 3 vertex id(s) of the same geometry.
    -- Same keying and the same reason for no foreign keys as tgsis.vrtx.
    CREATE TABLE tgsis.trgl (
        geoid  bigint NOT NULL,
        trglid bigint NOT NULL,
        vrtxid1 bigint NOT NULL,
        vrtxid2 bigint NOT NULL,
        vrtxid3 bigint NOT NULL,
        CONSTRAINT trgl_distinct_vertices CHECK (vrtxid1 <> vrtxid2 AND vrtxid1 <> vrtxid3 AND vrtxid2 <> vrtxid3),
        PRIMARY KEY (geoid, trglid)
    );

    COMMENT ON TABLE tgsis.trgl IS 'model 1: triangles of SURFACE geometries, keyed by (geoid, trglid)';
    COMMENT ON COLUMN tgsis.trgl.geoid IS 'geometry (tgsis.geometry.geoid)';
    COMMENT ON COLUMN tgsis.trgl.trglid IS 'simplex id, local to the geometry; _idx of CELL-aligned properties';
    COMMENT ON COLUMN tgsis.trgl.vrtxid1 IS 'vertex 1 (tgsis.vrtx.vrtxid of the same geoid)';
    COMMENT ON COLUMN tgsis.trgl.vrtxid2 IS 'vertex 2 (tgsis.vrtx.vrtxid of the same geoid)';
    COMMENT ON COLUMN tgsis.trgl.vrtxid3 IS 'vertex 3 (tgsis.vrtx.vrtxid of the same geoid)';

    -- ---- tgsis.tetra
    -- Tetrahedra of MULTITETRA geometries: each row points at 4 vertex id(s) of the same geometry.
    -- Same keying and the same reason for no foreign keys as tgsis.vrtx.
    CREATE TABLE tgsis.tetra (
        geoid  bigint NOT NULL,
        tetraid bigint NOT NULL,
        vrtxid1 bigint NOT NULL,
        vrtxid2 bigint NOT NULL,
        vrtxid3 bigint NOT NULL,
        vrtxid4 bigint NOT NULL,
        CONSTRAINT tetra_distinct_vertices CHECK (vrtxid1 <> vrtxid2 AND vrtxid1 <> vrtxid3 AND vrtxid1 <> vrtxid4 AND vrtxid2 <> vrtxid3 AND vrtxid2 <> vrtxid4 AND vrtxid3 <> vrtxid4),
        PRIMARY KEY (geoid, tetraid)
    );

    COMMENT ON TABLE tgsis.tetra IS 'model 1: tetrahedra of MULTITETRA geometries, keyed by (geoid, tetraid)';
    COMMENT ON COLUMN tgsis.tetra.geoid IS 'geometry (tgsis.geometry.geoid)';
    COMMENT ON COLUMN tgsis.tetra.tetraid IS 'simplex id, local to the geometry; _idx of CELL-aligned properties';
    COMMENT ON COLUMN tgsis.tetra.vrtxid1 IS 'vertex 1 (tgsis.vrtx.vrtxid of the same geoid)';
    COMMENT ON COLUMN tgsis.tetra.vrtxid2 IS 'vertex 2 (tgsis.vrtx.vrtxid of the same geoid)';
    COMMENT ON COLUMN tgsis.tetra.vrtxid3 IS 'vertex 3 (tgsis.vrtx.vrtxid of the same geoid)';
    COMMENT ON COLUMN tgsis.tetra.vrtxid4 IS 'vertex 4 (tgsis.vrtx.vrtxid of the same geoid)';

    -- ---- tgsis.atom
    -- Vertices that repeat another vertex of the same geometry (GOCAD ATOM and
    -- PATOM: parts of a surface that share a vertex, or a surface cut along a
    -- line). Few rows per geometry, so a side table rather than a column of
    -- every tgsis.vrtx row (bulk transfer speed, docs/performance.md). The
    -- atom's own vertex row keeps its position (equal to the one it repeats)
    -- and its properties (a PATOM may have values of its own).
    CREATE TABLE tgsis.atom (
        geoid  bigint NOT NULL,
        vrtxid bigint NOT NULL,
        refid  bigint NOT NULL,
        patom  boolean NOT NULL DEFAULT false,
        CONSTRAINT atom_not_itself CHECK (vrtxid <> refid),
        PRIMARY KEY (geoid, vrtxid)
    );

    COMMENT ON TABLE tgsis.atom IS
        'model 1: vertices that repeat another vertex of the same geometry (GOCAD ATOM/PATOM), keyed by (geoid, vrtxid)';
    COMMENT ON COLUMN tgsis.atom.geoid IS 'geometry (tgsis.geometry.geoid)';
    COMMENT ON COLUMN tgsis.atom.vrtxid IS 'the repeating vertex (tgsis.vrtx.vrtxid of the same geoid)';
    COMMENT ON COLUMN tgsis.atom.refid IS 'the vertex it repeats (tgsis.vrtx.vrtxid of the same geoid)';
    COMMENT ON COLUMN tgsis.atom.patom IS 'the file wrote it as a PATOM (an atom in an object with vertex properties), not an ATOM';

    -- ---- tgsis.part
    -- Parts of a geometry (GOCAD TFACE, ILINE, TVOLUME) as ranges of simplex
    -- ids: simplices firstid..lastid belong to part `part`. A file's parts are
    -- runs of cells, so a few rows describe them; a side table rather than a
    -- column of every simplex row, for the same reason as tgsis.atom. A
    -- geometry without rows here has one part.
    CREATE TABLE tgsis.part (
        geoid   bigint  NOT NULL,
        firstid bigint  NOT NULL,
        lastid  bigint  NOT NULL,
        part    integer NOT NULL CHECK (part >= 0),
        CONSTRAINT part_range CHECK (lastid >= firstid),
        PRIMARY KEY (geoid, firstid)
    );

    COMMENT ON TABLE tgsis.part IS
        'model 1: parts of geometries (GOCAD TFACE/ILINE/TVOLUME) as ranges of simplex ids, keyed by (geoid, firstid)';
    COMMENT ON COLUMN tgsis.part.geoid IS 'geometry (tgsis.geometry.geoid)';
    COMMENT ON COLUMN tgsis.part.firstid IS 'first simplex id of the range (pointid, segid, trglid or tetraid)';
    COMMENT ON COLUMN tgsis.part.lastid IS 'last simplex id of the range (inclusive)';
    COMMENT ON COLUMN tgsis.part.part IS 'part number (0, 1, ... in file order): the cell property part of the mesh';
END
$storage$;

REVOKE ALL ON FUNCTION tgsis.create_model1_storage() FROM PUBLIC;

COMMENT ON FUNCTION tgsis.create_model1_storage() IS
    'create the model-1 tables (vrtx, point, segment, trgl, tetra, atom, part; registered in tgsis.model_tables); called once by tgsis.create_storage';

-- the registry rows of model 1 (geometry/data_models.sql says why)
INSERT INTO tgsis.data_models (model, name, timemodel, geotypes, create_function, extent_function, check_function, description)
VALUES (1, 'static 3D objects', 'STATIC', '{MULTIPOINT,MULTILINESTRING,SURFACE,MULTITETRA,GEOMETRYCOLLECTION}',
        'create_model1_storage', 'static_extent', 'check_static_geometry',
        'objects that do not change in time: vertices and the simplices (points, segments, triangles, tetrahedra) that point at them');
INSERT INTO tgsis.model_tables (tablename, model, iudorder, geotype, description) VALUES
    ('vrtx',    1, 1, NULL,              'a vertex of a static geometry'),
    ('point',   1, 2, 'MULTIPOINT',      'a point of a MULTIPOINT geometry'),
    ('segment', 1, 2, 'MULTILINESTRING', 'a segment of a MULTILINESTRING geometry'),
    ('trgl',    1, 2, 'SURFACE',         'a triangle of a SURFACE geometry'),
    ('tetra',   1, 2, 'MULTITETRA',      'a tetrahedron of a MULTITETRA geometry'),
    ('atom',    1, 2, NULL,              'a vertex repeating another one (GOCAD ATOM/PATOM)'),
    ('part',    1, 2, NULL,              'a range of simplices forming a part (GOCAD TFACE/ILINE/TVOLUME)');

-- ==== model2/storage.sql ====
-- tgsis.create_model2_storage(): create the tables of model 2 (surfaces at instants: instants, vertices and triangles per instant) and register them.
-- Called by tgsis.create_storage (core/create_storage.sql says why the tables
-- are created by a function after CREATE EXTENSION, not by the script).
-- The search path is the script's (tgsis, cube's schema).
CREATE FUNCTION tgsis.create_model2_storage()
RETURNS void
LANGUAGE plpgsql
VOLATILE
SET search_path FROM CURRENT
AS $storage$
BEGIN
    -- ---- tgsis.times
    -- Model 2 (surfaces at instants): the instants at which each surface is known.
    -- Between two instants the surface is constant (a step function, left- or
    -- right-closed as the query chooses); its shape at an instant is in
    -- tgsis.times_vrtx and tgsis.times_trgl under the same (geoid, times).
    CREATE TABLE tgsis.times (
        geoid bigint           NOT NULL,
        times double precision NOT NULL CHECK (times > '-Infinity' AND times < 'Infinity'),
        PRIMARY KEY (geoid, times)
    );

    COMMENT ON TABLE tgsis.times IS 'model 2: the instants t0 < t1 < ... at which a surface (tgsis.geometry, timemodel INSTANTS) is known';
    COMMENT ON COLUMN tgsis.times.geoid IS 'geometry (tgsis.geometry.geoid)';
    COMMENT ON COLUMN tgsis.times.times IS 'instant in model time (larger is later; unit in tgsis.catalog.timeunit)';

    -- ---- tgsis.times_vrtx
    -- Model 2: vertices of a surface at one of its instants; ids are local to
    -- (geoid, times), 0..n-1 when uploaded.
    CREATE TABLE tgsis.times_vrtx (
        geoid  bigint           NOT NULL,
        times  double precision NOT NULL,
        vrtxid bigint           NOT NULL,
        x      double precision NOT NULL,
        y      double precision NOT NULL,
        z      double precision NOT NULL,
        PRIMARY KEY (geoid, times, vrtxid)
    );

    COMMENT ON TABLE tgsis.times_vrtx IS 'model 2: vertices of a surface at an instant, keyed by (geoid, times, vrtxid)';
    COMMENT ON COLUMN tgsis.times_vrtx.geoid IS 'geometry (tgsis.geometry.geoid)';
    COMMENT ON COLUMN tgsis.times_vrtx.times IS 'the instant (tgsis.times.times)';
    COMMENT ON COLUMN tgsis.times_vrtx.vrtxid IS 'vertex id, local to the geometry and instant';
    COMMENT ON COLUMN tgsis.times_vrtx.x IS 'x coordinate (unit of the class''s SRS)';
    COMMENT ON COLUMN tgsis.times_vrtx.y IS 'y coordinate';
    COMMENT ON COLUMN tgsis.times_vrtx.z IS 'z coordinate (up positive)';

    -- ---- tgsis.times_trgl
    -- Model 2: triangles of a surface at one of its instants, pointing at
    -- tgsis.times_vrtx rows of the same (geoid, times).
    CREATE TABLE tgsis.times_trgl (
        geoid   bigint           NOT NULL,
        times   double precision NOT NULL,
        trglid  bigint           NOT NULL,
        vrtxid1 bigint           NOT NULL,
        vrtxid2 bigint           NOT NULL,
        vrtxid3 bigint           NOT NULL,
        CONSTRAINT times_trgl_distinct_vertices CHECK (vrtxid1 <> vrtxid2 AND vrtxid1 <> vrtxid3 AND vrtxid2 <> vrtxid3),
        PRIMARY KEY (geoid, times, trglid)
    );

    COMMENT ON TABLE tgsis.times_trgl IS 'model 2: triangles of a surface at an instant, keyed by (geoid, times, trglid)';
    COMMENT ON COLUMN tgsis.times_trgl.geoid IS 'geometry (tgsis.geometry.geoid)';
    COMMENT ON COLUMN tgsis.times_trgl.times IS 'the instant (tgsis.times.times)';
    COMMENT ON COLUMN tgsis.times_trgl.trglid IS 'triangle id, local to the geometry and instant; _idx of CELL-aligned properties';
    COMMENT ON COLUMN tgsis.times_trgl.vrtxid1 IS 'vertex 1 (tgsis.times_vrtx.vrtxid of the same geoid and instant)';
    COMMENT ON COLUMN tgsis.times_trgl.vrtxid2 IS 'vertex 2 (tgsis.times_vrtx.vrtxid of the same geoid and instant)';
    COMMENT ON COLUMN tgsis.times_trgl.vrtxid3 IS 'vertex 3 (tgsis.times_vrtx.vrtxid of the same geoid and instant)';
END
$storage$;

REVOKE ALL ON FUNCTION tgsis.create_model2_storage() FROM PUBLIC;

COMMENT ON FUNCTION tgsis.create_model2_storage() IS
    'create the model-2 tables (times, times_vrtx, times_trgl); called once by tgsis.create_storage';

-- the registry rows of model 2 (geometry/data_models.sql says why)
INSERT INTO tgsis.data_models (model, name, timemodel, geotypes, timekey, create_function, extent_function, check_function,
                               description)
VALUES (2, 'surfaces at instants', 'INSTANTS', '{SURFACE}',
        '[{"name": "_times", "comment": "instant (model time) the values belong to: one of tgsis.times of the feature"}]',
        'create_model2_storage', 'instants_extent', 'check_temporal_geometry',
        'surfaces known at instants t0 < t1 < ..., constant in between (a shape per instant)');
INSERT INTO tgsis.model_tables (tablename, model, iudorder, description) VALUES
    ('times',      2, 1, 'an instant at which a surface is known'),
    ('times_vrtx', 2, 2, 'a vertex of a surface at one of its instants'),
    ('times_trgl', 2, 2, 'a triangle of a surface at one of its instants');

-- ==== model3/storage.sql ====
-- tgsis.create_model3_storage(): create the tables of model 3 (continuously evolving surfaces: topology and geometry instants, nodes, 4D triangles and vertices) and register them.
-- Called by tgsis.create_storage (core/create_storage.sql says why the tables
-- are created by a function after CREATE EXTENSION, not by the script).
-- The search path is the script's (tgsis, cube's schema).
CREATE FUNCTION tgsis.create_model3_storage()
RETURNS void
LANGUAGE plpgsql
VOLATILE
SET search_path FROM CURRENT
AS $storage$
BEGIN
    -- ---- tgsis.timem
    -- Model 3 (continuously evolving surfaces): the instants TM at which a
    -- surface's topology is (re)defined. Each starts a topology period that
    -- lasts until the next one (the last: until its last geometry instant, or for
    -- ever if the geometry is alive).
    CREATE TABLE tgsis.timem (
        geoid bigint           NOT NULL,
        timem double precision NOT NULL CHECK (timem > '-Infinity' AND timem < 'Infinity'),
        PRIMARY KEY (geoid, timem)
    );

    COMMENT ON TABLE tgsis.timem IS 'model 3: topology instants t0 < ... < tk of an evolving surface (tgsis.geometry, timemodel EVOLVING)';
    COMMENT ON COLUMN tgsis.timem.geoid IS 'geometry (tgsis.geometry.geoid)';
    COMMENT ON COLUMN tgsis.timem.timem IS 'instant where the topology is (re)defined; starts a topology period';

    -- ---- tgsis.timet
    -- Model 3: the geometry instants of each topology period. The first is the
    -- period's start; the last of a period that is not the last is the next
    -- period's start (both periods hold a shape at that instant).
    CREATE TABLE tgsis.timet (
        geoid bigint           NOT NULL,
        timem double precision NOT NULL,
        timet double precision NOT NULL CHECK (timet > '-Infinity' AND timet < 'Infinity'),
        CONSTRAINT timet_within_period CHECK (timet >= timem),
        PRIMARY KEY (geoid, timem, timet)
    );

    COMMENT ON TABLE tgsis.timet IS 'model 3: geometry instants of each topology period; node positions are known there and linear in between';
    COMMENT ON COLUMN tgsis.timet.geoid IS 'geometry (tgsis.geometry.geoid)';
    COMMENT ON COLUMN tgsis.timet.timem IS 'the topology period (tgsis.timem.timem)';
    COMMENT ON COLUMN tgsis.timet.timet IS 'geometry instant, >= timem';

    -- ---- tgsis.node
    -- Model 3: the nodes (abstract vertices) of each topology period. Node ids
    -- are unique within their geometry (the write path numbers them on through
    -- the periods), so a node belongs to one period.
    CREATE TABLE tgsis.node (
        geoid  bigint           NOT NULL,
        timem  double precision NOT NULL,
        nodeid bigint           NOT NULL,
        PRIMARY KEY (geoid, timem, nodeid)
    );

    COMMENT ON TABLE tgsis.node IS 'model 3: nodes (vertices of the topology) of each topology period';
    COMMENT ON COLUMN tgsis.node.geoid IS 'geometry (tgsis.geometry.geoid)';
    COMMENT ON COLUMN tgsis.node.timem IS 'the topology period (tgsis.timem.timem)';
    COMMENT ON COLUMN tgsis.node.nodeid IS 'node id, unique within the geometry; _idx of VERTEX-aligned properties';

    -- ---- tgsis.d4dtrgl
    -- Model 3: the triangles of each topology period, pointing at its nodes.
    -- They stay the same through the period while the nodes move.
    CREATE TABLE tgsis.d4dtrgl (
        geoid   bigint           NOT NULL,
        timem   double precision NOT NULL,
        trglid  bigint           NOT NULL,
        nodeid1 bigint           NOT NULL,
        nodeid2 bigint           NOT NULL,
        nodeid3 bigint           NOT NULL,
        CONSTRAINT d4dtrgl_distinct_nodes CHECK (nodeid1 <> nodeid2 AND nodeid1 <> nodeid3 AND nodeid2 <> nodeid3),
        PRIMARY KEY (geoid, timem, trglid)
    );

    COMMENT ON TABLE tgsis.d4dtrgl IS 'model 3: triangles of each topology period of an evolving surface';
    COMMENT ON COLUMN tgsis.d4dtrgl.geoid IS 'geometry (tgsis.geometry.geoid)';
    COMMENT ON COLUMN tgsis.d4dtrgl.timem IS 'the topology period (tgsis.timem.timem)';
    COMMENT ON COLUMN tgsis.d4dtrgl.trglid IS 'triangle id, unique within the geometry; _idx of CELL-aligned properties';
    COMMENT ON COLUMN tgsis.d4dtrgl.nodeid1 IS 'node 1 (tgsis.node.nodeid of the same geoid and period)';
    COMMENT ON COLUMN tgsis.d4dtrgl.nodeid2 IS 'node 2 (tgsis.node.nodeid of the same geoid and period)';
    COMMENT ON COLUMN tgsis.d4dtrgl.nodeid3 IS 'node 3 (tgsis.node.nodeid of the same geoid and period)';

    -- ---- tgsis.d4dvrtx
    -- Model 3: node positions at each geometry instant of their period. Between
    -- two geometry instants a node moves on the straight line between them.
    CREATE TABLE tgsis.d4dvrtx (
        geoid  bigint           NOT NULL,
        timem  double precision NOT NULL,
        timet  double precision NOT NULL,
        nodeid bigint           NOT NULL,
        x      double precision NOT NULL,
        y      double precision NOT NULL,
        z      double precision NOT NULL,
        PRIMARY KEY (geoid, timem, timet, nodeid)
    );

    COMMENT ON TABLE tgsis.d4dvrtx IS 'model 3: position of every node at every geometry instant of its period (4D vertices)';
    COMMENT ON COLUMN tgsis.d4dvrtx.geoid IS 'geometry (tgsis.geometry.geoid)';
    COMMENT ON COLUMN tgsis.d4dvrtx.timem IS 'the topology period (tgsis.timem.timem)';
    COMMENT ON COLUMN tgsis.d4dvrtx.timet IS 'the geometry instant (tgsis.timet.timet of the period)';
    COMMENT ON COLUMN tgsis.d4dvrtx.nodeid IS 'the node (tgsis.node.nodeid)';
    COMMENT ON COLUMN tgsis.d4dvrtx.x IS 'x coordinate at timet (unit of the class''s SRS)';
    COMMENT ON COLUMN tgsis.d4dvrtx.y IS 'y coordinate at timet';
    COMMENT ON COLUMN tgsis.d4dvrtx.z IS 'z coordinate at timet (up positive)';
END
$storage$;

REVOKE ALL ON FUNCTION tgsis.create_model3_storage() FROM PUBLIC;

COMMENT ON FUNCTION tgsis.create_model3_storage() IS
    'create the model-3 tables (timem, timet, node, d4dtrgl, d4dvrtx); called once by tgsis.create_storage';

-- the registry rows of model 3 (geometry/data_models.sql says why)
INSERT INTO tgsis.data_models (model, name, timemodel, geotypes, timekey, create_function, extent_function, check_function,
                               description)
VALUES (3, 'continuously evolving surfaces', 'EVOLVING', '{SURFACE}',
        '[{"name": "_timem", "comment": "topology period (its start, tgsis.timem) the values belong to"},
          {"name": "_timet", "comment": "geometry instant (tgsis.timet of the period) the values belong to; values are linear in between"}]',
        'create_model3_storage', 'evolving_extent', 'check_temporal_geometry',
        'surfaces whose nodes move linearly between geometry instants, with topology periods');
INSERT INTO tgsis.model_tables (tablename, model, iudorder, description) VALUES
    ('timem',   3, 1, 'a topology instant (start of a topology period) of an evolving surface'),
    ('timet',   3, 2, 'a geometry instant of a topology period'),
    ('node',    3, 2, 'a node (vertex of the topology) of a topology period'),
    ('d4dtrgl', 3, 2, 'a triangle of a topology period'),
    ('d4dvrtx', 3, 2, 'the position of a node at a geometry instant of its period');

-- ==== model4/storage.sql ====
-- tgsis.create_model4_storage(): create the tables of model 4 (n-G-maps in R^m evolving in valid time) and register them.
-- The spec's relations (feature, timem, timet, node, vertex, dart, alpha,
-- abstractcell) with the names prefixed gmap_ where model 3 has the same
-- ones; a feature is its tgsis.geometry row (geotype and time model GMAP,
-- alive) with the G-map's dimensions in tgsis.gmap. Times are keys as in
-- model 3 (a period is its start timem, an instant its value timet).
-- Called by tgsis.create_storage (core/create_storage.sql says why the
-- tables are created by a function after CREATE EXTENSION).
-- The search path is the script's (tgsis, cube's schema).
CREATE FUNCTION tgsis.create_model4_storage()
RETURNS void
LANGUAGE plpgsql
VOLATILE
SET search_path FROM CURRENT
AS $storage$
BEGIN
    -- ---- tgsis.gmap
    CREATE TABLE tgsis.gmap (
        geoid     bigint   PRIMARY KEY,
        dimension smallint NOT NULL CHECK (dimension >= 0),
        embedding smallint NOT NULL,
        CONSTRAINT gmap_embedding CHECK (embedding >= greatest(dimension, 1))
    );

    COMMENT ON TABLE tgsis.gmap IS 'model 4: one row per G-map geometry (tgsis.geometry, geotype GMAP): its dimensions';
    COMMENT ON COLUMN tgsis.gmap.geoid IS 'geometry (tgsis.geometry.geoid)';
    COMMENT ON COLUMN tgsis.gmap.dimension IS 'n: the involutions are alpha_0 .. alpha_n (levels 0..n of tgsis.gmap_alpha)';
    COMMENT ON COLUMN tgsis.gmap.embedding IS 'm >= n: the points of the embedding are in R^m (tgsis.gmap_vertex.coordinate has m values)';

    -- ---- tgsis.gmap_timem
    CREATE TABLE tgsis.gmap_timem (
        geoid bigint           NOT NULL,
        timem double precision NOT NULL CHECK (timem > '-Infinity' AND timem < 'Infinity'),
        PRIMARY KEY (geoid, timem)
    );

    COMMENT ON TABLE tgsis.gmap_timem IS 'model 4: topology instants t0 < ... < tk of a G-map; each starts a topology period with its own darts';
    COMMENT ON COLUMN tgsis.gmap_timem.geoid IS 'geometry (tgsis.geometry.geoid)';
    COMMENT ON COLUMN tgsis.gmap_timem.timem IS 'instant where the topology is (re)defined; the key of its period (the spec''s timemid)';

    -- ---- tgsis.gmap_timet
    CREATE TABLE tgsis.gmap_timet (
        geoid bigint           NOT NULL,
        timem double precision NOT NULL,
        timet double precision NOT NULL CHECK (timet > '-Infinity' AND timet < 'Infinity'),
        CONSTRAINT gmap_timet_within_period CHECK (timet >= timem),
        PRIMARY KEY (geoid, timem, timet)
    );

    COMMENT ON TABLE tgsis.gmap_timet IS 'model 4: geometry instants of each topology period; points are known there and linear in between';
    COMMENT ON COLUMN tgsis.gmap_timet.geoid IS 'geometry (tgsis.geometry.geoid)';
    COMMENT ON COLUMN tgsis.gmap_timet.timem IS 'the topology period (tgsis.gmap_timem.timem)';
    COMMENT ON COLUMN tgsis.gmap_timet.timet IS 'geometry instant, >= timem (the spec''s timeid)';

    -- ---- tgsis.gmap_node
    CREATE TABLE tgsis.gmap_node (
        geoid  bigint           NOT NULL,
        timem  double precision NOT NULL,
        nodeid bigint           NOT NULL,
        PRIMARY KEY (geoid, timem, nodeid)
    );

    COMMENT ON TABLE tgsis.gmap_node IS
        'model 4: the points of the embedding of each topology period (the spec''s redundant Node relation: darts point at them, positions are in tgsis.gmap_vertex)';
    COMMENT ON COLUMN tgsis.gmap_node.geoid IS 'geometry (tgsis.geometry.geoid)';
    COMMENT ON COLUMN tgsis.gmap_node.timem IS 'the topology period (tgsis.gmap_timem.timem)';
    COMMENT ON COLUMN tgsis.gmap_node.nodeid IS 'node id, unique within the geometry (numbered on through the periods)';

    -- ---- tgsis.gmap_vertex
    CREATE TABLE tgsis.gmap_vertex (
        geoid      bigint             NOT NULL,
        timem      double precision   NOT NULL,
        timet      double precision   NOT NULL,
        nodeid     bigint             NOT NULL,
        coordinate double precision[] NOT NULL,
        CONSTRAINT gmap_vertex_coordinate CHECK (array_ndims(coordinate) = 1 AND array_lower(coordinate, 1) = 1
                                                 AND array_position(coordinate, NULL) IS NULL),
        PRIMARY KEY (geoid, timem, timet, nodeid)
    );

    COMMENT ON TABLE tgsis.gmap_vertex IS 'model 4: the embedding: the point of every node at every geometry instant of its period';
    COMMENT ON COLUMN tgsis.gmap_vertex.geoid IS 'geometry (tgsis.geometry.geoid)';
    COMMENT ON COLUMN tgsis.gmap_vertex.timem IS 'the topology period (tgsis.gmap_timem.timem)';
    COMMENT ON COLUMN tgsis.gmap_vertex.timet IS 'the geometry instant (tgsis.gmap_timet.timet of the period)';
    COMMENT ON COLUMN tgsis.gmap_vertex.nodeid IS 'the node (tgsis.gmap_node.nodeid)';
    COMMENT ON COLUMN tgsis.gmap_vertex.coordinate IS 'the point in R^m (m = tgsis.gmap.embedding values; the first three are x, y, z, up positive)';

    -- ---- tgsis.gmap_dart
    CREATE TABLE tgsis.gmap_dart (
        geoid    bigint           NOT NULL,
        dartid   bigint           NOT NULL,
        timem    double precision NOT NULL,
        nodeid   bigint           NOT NULL,
        acellid  bigint,
        positive boolean,
        PRIMARY KEY (geoid, dartid)
    );

    COMMENT ON TABLE tgsis.gmap_dart IS 'model 4: the darts of each topology period';
    COMMENT ON COLUMN tgsis.gmap_dart.geoid IS 'geometry (tgsis.geometry.geoid)';
    COMMENT ON COLUMN tgsis.gmap_dart.dartid IS 'dart id, unique within the geometry (numbered on through the periods)';
    COMMENT ON COLUMN tgsis.gmap_dart.timem IS 'the topology period the dart belongs to (tgsis.gmap_timem.timem); every involution keeps it there';
    COMMENT ON COLUMN tgsis.gmap_dart.nodeid IS 'the point of the dart (tgsis.gmap_node.nodeid); all darts of one 0-cell share it';
    COMMENT ON COLUMN tgsis.gmap_dart.acellid IS
        'the cell of the feature class''s property level that holds the dart (tgsis.gmap_cell.acellid; _idx of the class''s properties); NULL: no property level';
    COMMENT ON COLUMN tgsis.gmap_dart.positive IS 'orientation of the dart (alternating along every involution) when the G-map is orientable; NULL otherwise';

    -- ---- tgsis.gmap_alpha
    -- One row per dart and involution, the free darts of alpha_n included
    -- (dartid2 = dartid): the spec's alpha relation with both directions of
    -- each pair, so that a check or an orbit step is one keyed join.
    CREATE TABLE tgsis.gmap_alpha (
        geoid   bigint   NOT NULL,
        level   smallint NOT NULL CHECK (level >= 0),
        dartid  bigint   NOT NULL,
        dartid2 bigint   NOT NULL,
        PRIMARY KEY (geoid, dartid, level)
    );

    COMMENT ON TABLE tgsis.gmap_alpha IS 'model 4: the involutions: alpha_level(dartid) = dartid2, one row per dart and level (dartid2 = dartid: free)';
    COMMENT ON COLUMN tgsis.gmap_alpha.geoid IS 'geometry (tgsis.geometry.geoid)';
    COMMENT ON COLUMN tgsis.gmap_alpha.level IS 'i of alpha_i, 0..n (tgsis.gmap.dimension)';
    COMMENT ON COLUMN tgsis.gmap_alpha.dartid IS 'the dart (tgsis.gmap_dart.dartid)';
    COMMENT ON COLUMN tgsis.gmap_alpha.dartid2 IS 'its image under alpha_level (itself when free, allowed only for level n)';

    -- ---- tgsis.gmap_cell
    CREATE TABLE tgsis.gmap_cell (
        geoid     bigint           NOT NULL,
        acellid   bigint           NOT NULL,
        timem     double precision NOT NULL,
        celllevel smallint         NOT NULL CHECK (celllevel >= 0),
        PRIMARY KEY (geoid, acellid)
    );

    COMMENT ON TABLE tgsis.gmap_cell IS
        'model 4: the abstract cells of the feature class''s property level (the spec''s abstractcell): properties attach to them';
    COMMENT ON COLUMN tgsis.gmap_cell.geoid IS 'geometry (tgsis.geometry.geoid)';
    COMMENT ON COLUMN tgsis.gmap_cell.acellid IS 'cell id, unique within the geometry; _idx of the class''s properties';
    COMMENT ON COLUMN tgsis.gmap_cell.timem IS 'the topology period of the cell (tgsis.gmap_timem.timem)';
    COMMENT ON COLUMN tgsis.gmap_cell.celllevel IS 'the cell''s dimension i (an i-cell: orbit of every involution but alpha_i)';
END
$storage$;

REVOKE ALL ON FUNCTION tgsis.create_model4_storage() FROM PUBLIC;

COMMENT ON FUNCTION tgsis.create_model4_storage() IS
    'create the model-4 tables (gmap, gmap_timem, gmap_timet, gmap_node, gmap_vertex, gmap_dart, gmap_alpha, gmap_cell; registered in tgsis.model_tables); called by tgsis.create_storage';

-- the registry rows of model 4 (geometry/data_models.sql says why)
INSERT INTO tgsis.data_models (model, name, timemodel, geotypes, timekey, cell_levels, create_function, extent_function,
                               check_function, description)
VALUES (4, 'generalized maps in time', 'GMAP', '{GMAP}',
        '[{"name": "_timem", "comment": "topology period (its start, tgsis.gmap_timem) the values belong to"},
          {"name": "_timet", "comment": "geometry instant (tgsis.gmap_timet of the period) the values belong to; values are linear in between"}]',
        true, 'create_model4_storage', 'gmap_extent', 'check_gmap_geometry',
        'n-dimensional objects with explicit topology (n-G-maps) embedded in R^m, with topology periods and points moving linearly between geometry instants');
INSERT INTO tgsis.model_tables (tablename, model, iudorder, description) VALUES
    ('gmap',        4, 1, 'the dimensions of a G-map'),
    ('gmap_timem',  4, 1, 'a topology instant (start of a topology period) of a G-map'),
    ('gmap_timet',  4, 2, 'a geometry instant of a topology period'),
    ('gmap_node',   4, 2, 'a point of the embedding of a topology period'),
    ('gmap_vertex', 4, 2, 'the position of a node at a geometry instant'),
    ('gmap_dart',   4, 2, 'a dart of a topology period'),
    ('gmap_alpha',  4, 2, 'the image of a dart under one involution'),
    ('gmap_cell',   4, 2, 'an abstract cell of the property level');

-- ==== model5/storage.sql ====
-- tgsis.create_model5_storage(): create the tables of model 5 (n-G-maps whose extra dimensions are time, knowledge or scale) and register them.
-- The spec's relations feature, vertex, dart, alpha, prefixed md_ (they
-- would clash with models 3 and 4); a feature is its tgsis.geometry row
-- (geotype GMAP, time model MULTIDIM) with its dimensions, the names of its
-- axes and its extent over all of them in tgsis.md_gmap. The extents and the
-- points are GiST-indexed as cubes (up to 100 dimensions), so that box
-- queries over any subset of the axes use an index (tgsis.md_in_box,
-- tgsis.md_vertices_in_box). Called by tgsis.create_storage.
-- The search path is the script's (tgsis, cube's schema).
CREATE FUNCTION tgsis.create_model5_storage()
RETURNS void
LANGUAGE plpgsql
VOLATILE
SET search_path FROM CURRENT
AS $storage$
BEGIN
    -- ---- tgsis.md_gmap
    CREATE TABLE tgsis.md_gmap (
        geoid     bigint   PRIMARY KEY,
        dimension smallint NOT NULL CHECK (dimension >= 0),
        embedding smallint NOT NULL CHECK (embedding BETWEEN 1 AND 100),
        axes      text[]   NOT NULL,
        extent    cube,
        CONSTRAINT md_gmap_embedding CHECK (embedding >= dimension),
        CONSTRAINT md_gmap_axes CHECK (cardinality(axes) = embedding AND array_position(axes, NULL) IS NULL),
        CONSTRAINT md_gmap_extent CHECK (extent IS NULL OR cube_dim(extent) = embedding)
    );
    CREATE INDEX md_gmap_extent_idx ON tgsis.md_gmap USING gist (extent);

    COMMENT ON TABLE tgsis.md_gmap IS 'model 5: one row per multiply indexed G-map (tgsis.geometry, time model MULTIDIM): its dimensions, axes and extent';
    COMMENT ON COLUMN tgsis.md_gmap.geoid IS 'geometry (tgsis.geometry.geoid)';
    COMMENT ON COLUMN tgsis.md_gmap.dimension IS 'n: the involutions are alpha_0 .. alpha_n (levels of tgsis.md_alpha)';
    COMMENT ON COLUMN tgsis.md_gmap.embedding IS 'm >= n (at most 100, the cube type''s limit): the points are in R^m';
    COMMENT ON COLUMN tgsis.md_gmap.axes IS 'the name of each of the m axes, in coordinate order (e.g. {x,y,z,knowledge})';
    COMMENT ON COLUMN tgsis.md_gmap.extent IS 'the box of every point over all m axes (NULL without points); GiST-indexed for tgsis.md_in_box';

    -- ---- tgsis.md_vertex
    CREATE TABLE tgsis.md_vertex (
        geoid      bigint             NOT NULL,
        vrtxid     bigint             NOT NULL,
        coordinate double precision[] NOT NULL,
        CONSTRAINT md_vertex_coordinate CHECK (array_ndims(coordinate) = 1 AND array_lower(coordinate, 1) = 1
                                               AND array_position(coordinate, NULL) IS NULL),
        PRIMARY KEY (geoid, vrtxid)
    );
    -- points of an object inside a box over any of its axes (the other axes unbounded)
    CREATE INDEX md_vertex_point_idx ON tgsis.md_vertex USING gist (cube(coordinate));

    COMMENT ON TABLE tgsis.md_vertex IS 'model 5: the points of the embedding (the spec''s vertex relation)';
    COMMENT ON COLUMN tgsis.md_vertex.geoid IS 'geometry (tgsis.geometry.geoid)';
    COMMENT ON COLUMN tgsis.md_vertex.vrtxid IS 'vertex id, local to the geometry';
    COMMENT ON COLUMN tgsis.md_vertex.coordinate IS 'the point in R^m, in the order of tgsis.md_gmap.axes';

    -- ---- tgsis.md_dart
    CREATE TABLE tgsis.md_dart (
        geoid    bigint  NOT NULL,
        dartid   bigint  NOT NULL,
        vrtxid   bigint  NOT NULL,
        acellid  bigint,
        positive boolean,
        PRIMARY KEY (geoid, dartid)
    );

    COMMENT ON TABLE tgsis.md_dart IS 'model 5: the darts';
    COMMENT ON COLUMN tgsis.md_dart.geoid IS 'geometry (tgsis.geometry.geoid)';
    COMMENT ON COLUMN tgsis.md_dart.dartid IS 'dart id, local to the geometry';
    COMMENT ON COLUMN tgsis.md_dart.vrtxid IS 'the point of the dart (tgsis.md_vertex.vrtxid); all darts of one 0-cell share it';
    COMMENT ON COLUMN tgsis.md_dart.acellid IS 'the cell of the feature class''s property level that holds the dart (tgsis.md_cell.acellid); NULL: none';
    COMMENT ON COLUMN tgsis.md_dart.positive IS 'orientation of the dart when the G-map is orientable; NULL otherwise';

    -- ---- tgsis.md_alpha
    CREATE TABLE tgsis.md_alpha (
        geoid   bigint   NOT NULL,
        level   smallint NOT NULL CHECK (level >= 0),
        dartid  bigint   NOT NULL,
        dartid2 bigint   NOT NULL,
        PRIMARY KEY (geoid, dartid, level)
    );

    COMMENT ON TABLE tgsis.md_alpha IS 'model 5: the involutions: alpha_level(dartid) = dartid2, one row per dart and level (dartid2 = dartid: free)';
    COMMENT ON COLUMN tgsis.md_alpha.geoid IS 'geometry (tgsis.geometry.geoid)';
    COMMENT ON COLUMN tgsis.md_alpha.level IS 'i of alpha_i, 0..n (tgsis.md_gmap.dimension)';
    COMMENT ON COLUMN tgsis.md_alpha.dartid IS 'the dart (tgsis.md_dart.dartid)';
    COMMENT ON COLUMN tgsis.md_alpha.dartid2 IS 'its image under alpha_level (itself when free, allowed only for level n)';

    -- ---- tgsis.md_cell
    CREATE TABLE tgsis.md_cell (
        geoid     bigint   NOT NULL,
        acellid   bigint   NOT NULL,
        celllevel smallint NOT NULL CHECK (celllevel >= 0),
        PRIMARY KEY (geoid, acellid)
    );

    COMMENT ON TABLE tgsis.md_cell IS 'model 5: the cells of the feature class''s property level: properties attach to them';
    COMMENT ON COLUMN tgsis.md_cell.geoid IS 'geometry (tgsis.geometry.geoid)';
    COMMENT ON COLUMN tgsis.md_cell.acellid IS 'cell id, local to the geometry; _idx of the class''s properties';
    COMMENT ON COLUMN tgsis.md_cell.celllevel IS 'the cell''s dimension i';
END
$storage$;

REVOKE ALL ON FUNCTION tgsis.create_model5_storage() FROM PUBLIC;

COMMENT ON FUNCTION tgsis.create_model5_storage() IS
    'create the model-5 tables (md_gmap, md_vertex, md_dart, md_alpha, md_cell; registered in tgsis.model_tables); called by tgsis.create_storage';

-- the registry rows of model 5 (geometry/data_models.sql says why)
INSERT INTO tgsis.data_models (model, name, timemodel, geotypes, cell_levels, create_function, extent_function,
                               check_function, description)
VALUES (5, 'multiply indexed G-maps', 'MULTIDIM', '{GMAP}', true, 'create_model5_storage', 'md_extent', 'check_md_geometry',
        'n-G-maps in R^m whose extra axes are time, knowledge, scale or uncertainty (a surface over knowledge is a volume)');
INSERT INTO tgsis.model_tables (tablename, model, iudorder, description) VALUES
    ('md_gmap',   5, 1, 'the dimensions, axes and extent of a multiply indexed G-map'),
    ('md_vertex', 5, 2, 'a point in R^m'),
    ('md_dart',   5, 2, 'a dart'),
    ('md_alpha',  5, 2, 'the image of a dart under one involution'),
    ('md_cell',   5, 2, 'a cell of the property level');

-- ==== core/create_storage.sql ====
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
-- from the script (core/storage.sql), so both routes leave the same objects.
-- The search path is the script's (tgsis, cube's schema): the tables use cube.
-- A model whose tables are all there is skipped, so the function also serves an
-- upgrade that registers a new model: its tables are created and granted, and
-- the geotype/time-model check of tgsis.geometry follows the registry.
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
    'create the tables of every registered data model (tgsis.data_models, tgsis.model_tables) that are missing, with their grants; returns whether it created any. Run by the plain-SQL script and by tgsis.install after CREATE EXTENSION, so that they are not extension members and pg_dump keeps them';

-- ==== core/storage.sql ====
-- The plain-SQL route creates the storage tables here, where the table files
-- used to be, so that the SQL functions below (checked when created on this
-- route) find them. Inside CREATE EXTENSION (pg_extension has the row while
-- the script runs) it does not: tables created here would be extension members
-- that pg_dump leaves out; tgsis.install calls tgsis.create_storage() right
-- after CREATE EXTENSION instead (core/create_storage.sql says why).
DO $do$
BEGIN
    IF NOT EXISTS (SELECT FROM pg_catalog.pg_extension WHERE extname = 'tgsis') THEN
        PERFORM tgsis.create_storage();
    END IF;
END
$do$;

-- ==== model1/simplex_table.sql ====
-- tgsis.simplex_table(geotype): the table holding the simplices of a geotype.
CREATE FUNCTION tgsis.simplex_table(p_geotype text)
RETURNS text
LANGUAGE sql
IMMUTABLE
PARALLEL SAFE
AS $$
    SELECT CASE upper(p_geotype)
               WHEN 'MULTIPOINT' THEN 'point'
               WHEN 'MULTILINESTRING' THEN 'segment'
               WHEN 'SURFACE' THEN 'trgl'
               WHEN 'MULTITETRA' THEN 'tetra'
           END
$$;

COMMENT ON FUNCTION tgsis.simplex_table(text) IS
    'name of the table (in schema tgsis) holding the simplices of a geotype: point, segment, trgl, tetra; NULL for GEOMETRYCOLLECTION';

-- ==== model1/static_extent.sql ====
-- tgsis.static_extent(geoid): bounding box and counts of a static (model-1) geometry from its vertex and simplex rows.
-- Model 1's extent function in the registry (tgsis.data_models), read by
-- tgsis.refresh_geometry. PL/pgSQL: the tables do not exist yet when the
-- extension script runs.
CREATE FUNCTION tgsis.static_extent(p_geoid bigint)
RETURNS TABLE (bbox cube, nvrtx bigint, ncell bigint)
LANGUAGE plpgsql
STABLE
SET search_path FROM CURRENT
AS $$
DECLARE
    v_table text;
BEGIN
    SELECT tgsis.simplex_table(g.geotype) INTO v_table FROM tgsis.geometry g WHERE g.geoid = p_geoid;
    EXECUTE format('SELECT count(*) FROM tgsis.%I WHERE geoid = $1', v_table) INTO ncell USING p_geoid;
    SELECT count(*),
           CASE WHEN count(*) > 0 THEN cube(ARRAY[min(v.x), min(v.y), min(v.z)], ARRAY[max(v.x), max(v.y), max(v.z)]) END
      INTO nvrtx, bbox
      FROM tgsis.vrtx v WHERE v.geoid = p_geoid;
    RETURN NEXT;
END
$$;

COMMENT ON FUNCTION tgsis.static_extent(bigint) IS
    'bbox (cube of the vertices, NULL without any), number of vertices and of simplices of a static geometry from tgsis.vrtx and its simplex table; model 1''s extent function (tgsis.data_models)';

-- ==== model1/check_static_geometry.sql ====
-- tgsis.check_static_geometry(geoid): what is wrong with a stored static (model-1) geometry (no rows: nothing).
-- Model 1's check function in the registry (tgsis.data_models), read by
-- tgsis.check_geometry: rows written by other means than the client's write
-- path may point at missing vertices or leave the bbox stale.
CREATE FUNCTION tgsis.check_static_geometry(p_geoid bigint)
RETURNS TABLE (problem text, count bigint, example text)
LANGUAGE plpgsql
STABLE
SET search_path FROM CURRENT
AS $$
DECLARE
    v_geo   record;
    v_table text;
    v_k     int;
    v_i     int;
BEGIN
    SELECT geotype, nvrtx, bbox INTO v_geo FROM tgsis.geometry WHERE geoid = p_geoid;
    RETURN QUERY SELECT 'vertex with a NaN or infinite coordinate'::text, count(*), min(vrtxid)::text
                   FROM tgsis.vrtx
                  WHERE geoid = p_geoid
                    AND (x IN ('NaN', 'Infinity', '-Infinity') OR y IN ('NaN', 'Infinity', '-Infinity')
                         OR z IN ('NaN', 'Infinity', '-Infinity'))
                 HAVING count(*) > 0;

    v_table := tgsis.simplex_table(v_geo.geotype);
    v_k := CASE v_table WHEN 'point' THEN 1 WHEN 'segment' THEN 2 WHEN 'trgl' THEN 3 ELSE 4 END;
    FOR v_i IN 1 .. v_k LOOP
        RETURN QUERY EXECUTE format(
            'SELECT %L::text, count(*), min(s.%I)::text FROM tgsis.%I s
              WHERE s.geoid = $1
                AND NOT EXISTS (SELECT FROM tgsis.vrtx v WHERE v.geoid = s.geoid AND v.vrtxid = s.%I)
             HAVING count(*) > 0',
            format('%s refers to a missing vertex (vrtxid%s)', v_table, v_i),
            CASE v_table WHEN 'point' THEN 'pointid' WHEN 'segment' THEN 'segid'
                         WHEN 'trgl' THEN 'trglid' ELSE 'tetraid' END,
            v_table, 'vrtxid' || v_i) USING p_geoid;
    END LOOP;

    -- atoms repeat a vertex at the same place; parts cover simplices that exist
    RETURN QUERY SELECT 'atom refers to a missing vertex'::text, count(*), min(a.vrtxid)::text
                   FROM tgsis.atom a
                  WHERE a.geoid = p_geoid
                    AND (NOT EXISTS (SELECT FROM tgsis.vrtx v WHERE v.geoid = a.geoid AND v.vrtxid = a.vrtxid)
                         OR NOT EXISTS (SELECT FROM tgsis.vrtx v WHERE v.geoid = a.geoid AND v.vrtxid = a.refid))
                 HAVING count(*) > 0;
    RETURN QUERY SELECT 'atom is not at the place of the vertex it repeats'::text, count(*), min(a.vrtxid)::text
                   FROM tgsis.atom a
                   JOIN tgsis.vrtx v ON v.geoid = a.geoid AND v.vrtxid = a.vrtxid
                   JOIN tgsis.vrtx r ON r.geoid = a.geoid AND r.vrtxid = a.refid
                  WHERE a.geoid = p_geoid AND (v.x, v.y, v.z) IS DISTINCT FROM (r.x, r.y, r.z)
                 HAVING count(*) > 0;
    RETURN QUERY SELECT 'part ranges overlap'::text, count(*), min(p.firstid)::text
                   FROM tgsis.part p
                  WHERE p.geoid = p_geoid
                    AND EXISTS (SELECT FROM tgsis.part q WHERE q.geoid = p.geoid AND q.firstid > p.firstid
                                                          AND q.firstid <= p.lastid)
                 HAVING count(*) > 0;

    RETURN QUERY
        SELECT 'bounding box or counts out of date (run tgsis.refresh_geometry)'::text, 1::bigint, NULL::text
          FROM (SELECT count(*) AS n,
                       CASE WHEN count(*) > 0
                            THEN cube(ARRAY[min(x), min(y), min(z)], ARRAY[max(x), max(y), max(z)]) END AS bbox
                  FROM tgsis.vrtx WHERE geoid = p_geoid) AS v
         WHERE v.n <> v_geo.nvrtx OR v.bbox IS DISTINCT FROM v_geo.bbox;
END
$$;

COMMENT ON FUNCTION tgsis.check_static_geometry(bigint) IS
    'problems of a stored static geometry: non-finite coordinates, simplices pointing at missing vertices, atoms of missing or moved vertices, overlapping part ranges, stale bbox/counts; model 1''s check function (tgsis.data_models)';

-- ==== model2/instants_extent.sql ====
-- tgsis.instants_extent(geoid): bounding box and counts of a surface at instants (model 2) over all its instants.
-- Model 2's extent function in the registry (tgsis.data_models), read by
-- tgsis.refresh_geometry.
CREATE FUNCTION tgsis.instants_extent(p_geoid bigint)
RETURNS TABLE (bbox cube, nvrtx bigint, ncell bigint)
LANGUAGE plpgsql
STABLE
SET search_path FROM CURRENT
AS $$
BEGIN
    SELECT count(*) INTO ncell FROM tgsis.times_trgl c WHERE c.geoid = p_geoid;
    SELECT count(*),
           CASE WHEN count(*) > 0 THEN cube(ARRAY[min(v.x), min(v.y), min(v.z)], ARRAY[max(v.x), max(v.y), max(v.z)]) END
      INTO nvrtx, bbox
      FROM tgsis.times_vrtx v WHERE v.geoid = p_geoid;
    RETURN NEXT;
END
$$;

COMMENT ON FUNCTION tgsis.instants_extent(bigint) IS
    'bbox of every vertex at every instant, number of vertex rows and of triangle rows of a surface at instants (model 2); model 2''s extent function (tgsis.data_models)';

-- ==== model3/evolving_extent.sql ====
-- tgsis.evolving_extent(geoid): bounding box and counts of an evolving surface (model 3) over all its periods.
-- Model 3's extent function in the registry (tgsis.data_models), read by
-- tgsis.refresh_geometry: the box holds every node position at every geometry
-- instant, which holds every shape in between (nodes move on straight lines).
CREATE FUNCTION tgsis.evolving_extent(p_geoid bigint)
RETURNS TABLE (bbox cube, nvrtx bigint, ncell bigint)
LANGUAGE plpgsql
STABLE
SET search_path FROM CURRENT
AS $$
BEGIN
    SELECT count(*) INTO ncell FROM tgsis.d4dtrgl c WHERE c.geoid = p_geoid;
    SELECT count(*) INTO nvrtx FROM tgsis.node n WHERE n.geoid = p_geoid;
    SELECT CASE WHEN count(*) > 0 THEN cube(ARRAY[min(v.x), min(v.y), min(v.z)], ARRAY[max(v.x), max(v.y), max(v.z)]) END
      INTO bbox
      FROM tgsis.d4dvrtx v WHERE v.geoid = p_geoid;
    RETURN NEXT;
END
$$;

COMMENT ON FUNCTION tgsis.evolving_extent(bigint) IS
    'bbox of every node position at every geometry instant, number of nodes and of triangles of an evolving surface (model 3) over all its periods; model 3''s extent function (tgsis.data_models)';

-- ==== temporal/check_temporal_geometry.sql ====
-- tgsis.check_temporal_geometry(geoid): what is wrong with the rows of a model-2 or model-3 geometry (no rows: nothing).
-- The client writes consistent rows; this checks rows edited with plain SQL,
-- which the snapshot would otherwise silently misread (a node without a
-- position at an instant drops out of the snapshot, a gap between periods
-- makes the surface vanish there).
CREATE FUNCTION tgsis.check_temporal_geometry(p_geoid bigint)
RETURNS TABLE (problem text, count bigint, example text)
LANGUAGE plpgsql
STABLE
AS $$
DECLARE
    v_geo record;
BEGIN
    SELECT timemodel, nvrtx, ncell, bbox INTO v_geo FROM tgsis.geometry WHERE geoid = p_geoid;
    IF NOT FOUND THEN
        RAISE EXCEPTION 'geometry % does not exist', p_geoid USING ERRCODE = 'TG200';
    END IF;
    IF v_geo.timemodel = 'INSTANTS' THEN
        RETURN QUERY SELECT 'vertex or triangle at an instant not in tgsis.times'::text, count(*), min(r.times)::text
                       FROM (SELECT v.times FROM tgsis.times_vrtx v WHERE v.geoid = p_geoid
                             UNION ALL SELECT c.times FROM tgsis.times_trgl c WHERE c.geoid = p_geoid) r
                      WHERE NOT EXISTS (SELECT FROM tgsis.times i WHERE i.geoid = p_geoid AND i.times = r.times)
                     HAVING count(*) > 0;
        RETURN QUERY SELECT 'triangle refers to a missing vertex of its instant'::text, count(*),
                            min(format('instant %s, trglid %s', c.times, c.trglid))
                       FROM tgsis.times_trgl c
                      WHERE c.geoid = p_geoid
                        AND EXISTS (SELECT FROM unnest(ARRAY[c.vrtxid1, c.vrtxid2, c.vrtxid3]) AS k(id)
                                     WHERE NOT EXISTS (SELECT FROM tgsis.times_vrtx v
                                                        WHERE v.geoid = p_geoid AND v.times = c.times AND v.vrtxid = k.id))
                     HAVING count(*) > 0;
        RETURN QUERY SELECT 'vertex with a NaN or infinite coordinate'::text, count(*),
                            min(format('instant %s, vrtxid %s', v.times, v.vrtxid))
                       FROM tgsis.times_vrtx v
                      WHERE v.geoid = p_geoid
                        AND ('NaN' IN (v.x, v.y, v.z) OR 'Infinity' IN (abs(v.x), abs(v.y), abs(v.z)))
                     HAVING count(*) > 0;
    ELSIF v_geo.timemodel = 'EVOLVING' THEN
        RETURN QUERY SELECT 'geometry instant of a period not in tgsis.timem'::text, count(*), min(t.timem)::text
                       FROM tgsis.timet t
                      WHERE t.geoid = p_geoid AND NOT EXISTS (SELECT FROM tgsis.timem m WHERE m.geoid = p_geoid AND m.timem = t.timem)
                     HAVING count(*) > 0;
        RETURN QUERY SELECT 'topology period without a geometry instant at its start'::text, count(*), min(m.timem)::text
                       FROM tgsis.timem m
                      WHERE m.geoid = p_geoid
                        AND NOT EXISTS (SELECT FROM tgsis.timet t WHERE t.geoid = p_geoid AND t.timem = m.timem AND t.timet = m.timem)
                     HAVING count(*) > 0;
        RETURN QUERY SELECT 'topology period does not end where the next one starts'::text, count(*), min(p.timem)::text
                       FROM (SELECT m.timem, lead(m.timem) OVER (ORDER BY m.timem) AS next,
                                    (SELECT max(t.timet) FROM tgsis.timet t WHERE t.geoid = p_geoid AND t.timem = m.timem) AS last
                               FROM tgsis.timem m WHERE m.geoid = p_geoid) p
                      WHERE p.next IS NOT NULL AND p.last IS DISTINCT FROM p.next
                     HAVING count(*) > 0;
        RETURN QUERY SELECT 'node without a position at a geometry instant of its period'::text, count(*),
                            min(format('nodeid %s at %s', n.nodeid, t.timet))
                       FROM tgsis.node n
                       JOIN tgsis.timet t ON t.geoid = p_geoid AND t.timem = n.timem
                      WHERE n.geoid = p_geoid
                        AND NOT EXISTS (SELECT FROM tgsis.d4dvrtx v WHERE v.geoid = p_geoid AND v.timem = n.timem
                                                                      AND v.timet = t.timet AND v.nodeid = n.nodeid)
                     HAVING count(*) > 0;
        RETURN QUERY SELECT 'position of a node or at an instant its period does not have'::text, count(*),
                            min(format('nodeid %s at %s', v.nodeid, v.timet))
                       FROM tgsis.d4dvrtx v
                      WHERE v.geoid = p_geoid
                        AND (NOT EXISTS (SELECT FROM tgsis.node n WHERE n.geoid = p_geoid AND n.timem = v.timem AND n.nodeid = v.nodeid)
                             OR NOT EXISTS (SELECT FROM tgsis.timet t WHERE t.geoid = p_geoid AND t.timem = v.timem AND t.timet = v.timet))
                     HAVING count(*) > 0;
        RETURN QUERY SELECT 'triangle refers to a missing node of its period'::text, count(*),
                            min(format('period %s, trglid %s', c.timem, c.trglid))
                       FROM tgsis.d4dtrgl c
                      WHERE c.geoid = p_geoid
                        AND EXISTS (SELECT FROM unnest(ARRAY[c.nodeid1, c.nodeid2, c.nodeid3]) AS k(id)
                                     WHERE NOT EXISTS (SELECT FROM tgsis.node n
                                                        WHERE n.geoid = p_geoid AND n.timem = c.timem AND n.nodeid = k.id))
                     HAVING count(*) > 0;
        RETURN QUERY SELECT 'node position with a NaN or infinite coordinate'::text, count(*),
                            min(format('nodeid %s at %s', v.nodeid, v.timet))
                       FROM tgsis.d4dvrtx v
                      WHERE v.geoid = p_geoid
                        AND ('NaN' IN (v.x, v.y, v.z) OR 'Infinity' IN (abs(v.x), abs(v.y), abs(v.z)))
                     HAVING count(*) > 0;
    END IF;
    RETURN QUERY
        SELECT 'bounding box or counts out of date (run tgsis.refresh_geometry)'::text, 1::bigint, NULL::text
          FROM (SELECT CASE v_geo.timemodel
                           WHEN 'INSTANTS' THEN (SELECT count(*) FROM tgsis.times_vrtx v WHERE v.geoid = p_geoid)
                           ELSE (SELECT count(*) FROM tgsis.node n WHERE n.geoid = p_geoid) END AS n,
                       CASE v_geo.timemodel
                           WHEN 'INSTANTS' THEN (SELECT count(*) FROM tgsis.times_trgl c WHERE c.geoid = p_geoid)
                           ELSE (SELECT count(*) FROM tgsis.d4dtrgl c WHERE c.geoid = p_geoid) END AS m,
                       (SELECT CASE WHEN count(*) > 0 THEN cube(ARRAY[min(x), min(y), min(z)], ARRAY[max(x), max(y), max(z)]) END
                          FROM (SELECT v.x, v.y, v.z FROM tgsis.times_vrtx v WHERE v.geoid = p_geoid
                                UNION ALL SELECT v.x, v.y, v.z FROM tgsis.d4dvrtx v WHERE v.geoid = p_geoid) xyz) AS bbox) s
         WHERE s.n <> v_geo.nvrtx OR s.m <> v_geo.ncell OR s.bbox IS DISTINCT FROM v_geo.bbox;
END
$$;

COMMENT ON FUNCTION tgsis.check_temporal_geometry(bigint) IS
    'problems of the rows of a model-2 or model-3 geometry: orphan instants, triangles pointing at missing vertices or nodes, nodes missing a position at an instant, periods that do not follow each other, non-finite coordinates, stale bbox/counts';

-- ==== geometry/new_geometry.sql ====
-- tgsis.new_geometry(geotype, name, bounds, nvrtx, ncell, geoids, collection, timemodel, alive, color, zpositive, crs, metadata): insert a geometry row and return its geoid.
-- The client's write path calls it before copying vertices and simplices;
-- bounds is {xmin, ymin, zmin, xmax, ymax, zmax} (NULL: no vertex); a member
-- stored with its GEOMETRYCOLLECTION names the collection that owns it.
-- zpositive, crs and metadata record what the file meant (z convention,
-- coordinate-system block, other format facts): bounds are in elevation
-- whatever zpositive says, as the vertices are.
CREATE FUNCTION tgsis.new_geometry(
    p_geotype    text,
    p_name       text,
    p_bounds     double precision[],
    p_nvrtx      bigint,
    p_ncell      bigint,
    p_geoids     bigint[] DEFAULT NULL,
    p_collection bigint   DEFAULT NULL,
    p_timemodel  text     DEFAULT 'STATIC',
    p_alive      boolean  DEFAULT false,
    p_color      real[]   DEFAULT NULL,
    p_zpositive  text     DEFAULT NULL,
    p_crs        jsonb    DEFAULT NULL,
    p_metadata   jsonb    DEFAULT NULL)
RETURNS bigint
LANGUAGE plpgsql
SET search_path FROM CURRENT
AS $$
DECLARE
    v_geoid bigint;
    v_owner text;
BEGIN
    PERFORM tgsis.plain_write_check('tgsis', 'geometry');  -- not "in" a version while features are plain
    -- geotypes and time models are the registered data models' (tgsis.data_models)
    IF NOT EXISTS (SELECT FROM tgsis.data_models m WHERE upper(p_geotype) = ANY (m.geotypes)) THEN
        RAISE EXCEPTION 'geotype % of a new geometry is unknown', coalesce(quote_literal(p_geotype), 'NULL')
            USING ERRCODE = 'TG102',
                  HINT = 'p_geotype => ' || tgsis.or_list(ARRAY(SELECT DISTINCT g FROM tgsis.data_models m, unnest(m.geotypes) AS g
                                                                 ORDER BY g));
    END IF;
    IF p_nvrtx IS NULL OR p_nvrtx < 0 OR p_ncell IS NULL OR p_ncell < 0 THEN
        RAISE EXCEPTION 'vertex and cell counts of a new geometry must be numbers >= 0, got p_nvrtx => % and p_ncell => %',
                        coalesce(p_nvrtx::text, 'NULL'), coalesce(p_ncell::text, 'NULL')
            USING ERRCODE = 'TG102', HINT = 'give the number of vertices and of cells (0 for none)';
    END IF;
    IF p_bounds IS NOT NULL AND (cardinality(p_bounds) <> 6 OR array_position(p_bounds, NULL) IS NOT NULL
                                 OR 'NaN' = ANY (p_bounds) OR 'Infinity' = ANY (p_bounds) OR '-Infinity' = ANY (p_bounds)) THEN
        RAISE EXCEPTION 'bounds of a new geometry must be 6 finite numbers {xmin, ymin, zmin, xmax, ymax, zmax}, got %', p_bounds
            USING ERRCODE = 'TG102';
    END IF;
    IF p_color IS NOT NULL AND (cardinality(p_color) <> 3 OR array_position(p_color, NULL) IS NOT NULL
                                OR EXISTS (SELECT FROM unnest(p_color) c WHERE NOT c BETWEEN 0 AND 1)) THEN
        RAISE EXCEPTION 'colour of a new geometry must be 3 numbers {red, green, blue} in [0, 1], got %', p_color
            USING ERRCODE = 'TG102';
    END IF;
    IF p_zpositive IS NOT NULL AND p_zpositive NOT IN ('Elevation', 'Depth') THEN
        RAISE EXCEPTION 'z convention % of a new geometry is unknown', quote_literal(p_zpositive)
            USING ERRCODE = 'TG102', HINT = 'p_zpositive => ''Elevation'' (up positive), ''Depth'' (down positive) or NULL';
    END IF;
    IF p_crs IS NOT NULL AND jsonb_typeof(p_crs) <> 'array' THEN
        RAISE EXCEPTION 'coordinate system of a new geometry must be a JSON array of the block''s lines, got %', jsonb_typeof(p_crs)
            USING ERRCODE = 'TG102', HINT = 'p_crs => ''["NAME Default", "ZPOSITIVE Depth"]'' or NULL';
    END IF;
    IF p_metadata IS NOT NULL AND jsonb_typeof(p_metadata) <> 'object' THEN
        RAISE EXCEPTION 'metadata of a new geometry must be a JSON object, got %', jsonb_typeof(p_metadata)
            USING ERRCODE = 'TG102', HINT = 'p_metadata => ''{}'' or NULL';
    END IF;
    IF NOT EXISTS (SELECT FROM tgsis.data_models m WHERE m.timemodel = upper(p_timemodel) AND upper(p_geotype) = ANY (m.geotypes)) THEN
        RAISE EXCEPTION 'time model % is not one of a % geometry', coalesce(quote_literal(p_timemodel), 'NULL'), upper(p_geotype)
            USING ERRCODE = 'TG102',
                  HINT = (SELECT string_agg(format('%s for %s', m.timemodel, tgsis.or_list(m.geotypes)), '; ' ORDER BY m.model)
                            FROM tgsis.data_models m WHERE m.model > 0);
    END IF;
    IF p_collection IS NOT NULL THEN
        IF upper(p_geotype) = 'GEOMETRYCOLLECTION' THEN
            RAISE EXCEPTION 'a GEOMETRYCOLLECTION cannot be a member of collection %: collections do not nest', p_collection
                USING ERRCODE = 'TG102', HINT = 'store the inner collection''s members in the outer one';
        END IF;
        SELECT geotype INTO v_owner FROM tgsis.geometry WHERE geoid = p_collection;
        IF NOT FOUND THEN
            RAISE EXCEPTION 'collection % of a new % geometry does not exist', p_collection, upper(p_geotype)
                USING ERRCODE = 'TG200';
        ELSIF v_owner <> 'GEOMETRYCOLLECTION' THEN
            RAISE EXCEPTION 'geometry % is a %, not a GEOMETRYCOLLECTION: it cannot own members', p_collection, v_owner
                USING ERRCODE = 'TG102';
        END IF;
    END IF;
    INSERT INTO tgsis.geometry (geotype, geoname, geoids, collection, bbox, nvrtx, ncell, timemodel, alive,
                                colorred, colorgreen, colorblue, zpositive, crs, metadata)
    VALUES (upper(p_geotype), p_name, p_geoids, p_collection,
            CASE WHEN p_bounds IS NOT NULL THEN cube(p_bounds[1:3], p_bounds[4:6]) END,
            p_nvrtx, p_ncell, upper(p_timemodel), coalesce(p_alive, false), p_color[1], p_color[2], p_color[3],
            p_zpositive, p_crs, p_metadata)
    RETURNING geoid INTO v_geoid;
    RETURN v_geoid;
END
$$;

COMMENT ON FUNCTION tgsis.new_geometry(text, text, double precision[], bigint, bigint, bigint[], bigint, text, boolean, real[], text, jsonb, jsonb) IS
    'insert a tgsis.geometry row (bounding box from {xmin, ymin, zmin, xmax, ymax, zmax} in elevation; members of a GEOMETRYCOLLECTION name their owning collection; time model, alive, colour {r, g, b}; the file''s z convention, coordinate-system block and other format metadata) and return its geoid';

-- ==== geometry/refresh_geometry.sql ====
-- tgsis.refresh_geometry(geoid): recompute a geometry's bounding box and counts from its rows.
-- The client's write path sets them itself; this is for edits made with plain SQL.
-- Returns the new values (not the table's row type: once model 1 is
-- versioned, tgsis.geometry is a view and its storage type has more columns).
CREATE FUNCTION tgsis.refresh_geometry(p_geoid bigint)
RETURNS TABLE (geoid bigint, bbox cube, nvrtx bigint, ncell bigint)
LANGUAGE plpgsql
SET search_path FROM CURRENT
AS $$
#variable_conflict use_column
DECLARE
    v_geotype text;
    v_model   text;
    v_bbox    cube;
    v_nvrtx   bigint;
    v_ncell   bigint;
    v_hook    text;
BEGIN
    SELECT g.geotype, g.timemodel INTO v_geotype, v_model FROM tgsis.geometry g WHERE g.geoid = p_geoid FOR UPDATE;
    IF NOT FOUND THEN
        RAISE EXCEPTION 'geometry % does not exist', p_geoid
            USING ERRCODE = 'TG200', HINT = 'SELECT geoid FROM tgsis.geometry lists the stored geometries';
    END IF;

    IF v_geotype = 'GEOMETRYCOLLECTION' THEN
        SELECT CASE WHEN count(m.bbox) > 0 THEN  -- members without vertices have no bbox
                    cube(ARRAY[min(cube_ll_coord(m.bbox, 1)), min(cube_ll_coord(m.bbox, 2)), min(cube_ll_coord(m.bbox, 3))],
                         ARRAY[max(cube_ur_coord(m.bbox, 1)), max(cube_ur_coord(m.bbox, 2)), max(cube_ur_coord(m.bbox, 3))])
               END,
               coalesce(sum(m.nvrtx), 0), coalesce(sum(m.ncell), 0)
          INTO v_bbox, v_nvrtx, v_ncell
          FROM tgsis.geometry m
         WHERE m.geoid = ANY ((SELECT c.geoids FROM tgsis.geometry c WHERE c.geoid = p_geoid)::bigint[]);
    ELSE
        -- the geometry's data model computes them from its own tables (tgsis.data_models.extent_function)
        SELECT m.extent_function INTO v_hook FROM tgsis.data_models m WHERE m.timemodel = v_model;
        EXECUTE format('SELECT e.bbox, e.nvrtx, e.ncell FROM tgsis.%I($1) e', v_hook)
           INTO v_bbox, v_nvrtx, v_ncell USING p_geoid;
    END IF;
    UPDATE tgsis.geometry g SET bbox = v_bbox, nvrtx = v_nvrtx, ncell = v_ncell WHERE g.geoid = p_geoid;
    RETURN QUERY SELECT p_geoid, v_bbox, v_nvrtx, v_ncell;
END
$$;

COMMENT ON FUNCTION tgsis.refresh_geometry(bigint) IS
    'recompute bbox, nvrtx and ncell of a geometry from its rows (after edits with plain SQL): a collection from its members, the others by their data model''s extent function (tgsis.data_models); returns them';

-- ==== geometry/geometries_in_box.sql ====
-- tgsis.geometries_in_box(xmin, ymin, zmin, xmax, ymax, zmax): geometries whose bounding box meets the box.
CREATE FUNCTION tgsis.geometries_in_box(
    p_xmin double precision, p_ymin double precision, p_zmin double precision,
    p_xmax double precision, p_ymax double precision, p_zmax double precision)
RETURNS SETOF bigint
LANGUAGE sql
STABLE
PARALLEL SAFE
SET search_path FROM CURRENT
AS $$
    SELECT geoid
      FROM tgsis.geometry
     WHERE bbox && cube(ARRAY[p_xmin, p_ymin, p_zmin], ARRAY[p_xmax, p_ymax, p_zmax])
     ORDER BY geoid
$$;

COMMENT ON FUNCTION tgsis.geometries_in_box(double precision, double precision, double precision,
                                            double precision, double precision, double precision) IS
    'ids of the geometries whose 3D bounding box intersects the given box (GiST index scan on tgsis.geometry.bbox)';

-- ==== geometry/check_geometry.sql ====
-- tgsis.check_geometry(geoid): what is wrong with a stored geometry (no rows: nothing).
-- The client validates before writing; this checks rows written by other means.
-- Collections are the core's; the rest is the geometry's data model's check.
CREATE FUNCTION tgsis.check_geometry(p_geoid bigint)
RETURNS TABLE (problem text, count bigint, example text)
LANGUAGE plpgsql
STABLE
SET search_path FROM CURRENT
AS $$
DECLARE
    v_geo   record;
    v_hook  text;
BEGIN
    SELECT geotype, geoids, nvrtx, ncell, bbox, timemodel INTO v_geo FROM tgsis.geometry WHERE geoid = p_geoid;
    IF NOT FOUND THEN
        RAISE EXCEPTION 'geometry % does not exist', p_geoid USING ERRCODE = 'TG200';
    END IF;
    IF v_geo.geotype = 'GEOMETRYCOLLECTION' THEN
        RETURN QUERY SELECT 'member geometry does not exist'::text, count(*), min(m)::text
                       FROM unnest(v_geo.geoids) AS m
                      WHERE NOT EXISTS (SELECT FROM tgsis.geometry g WHERE g.geoid = m)
                     HAVING count(*) > 0;
        RETURN QUERY SELECT 'member is a GEOMETRYCOLLECTION (collections do not nest)'::text, count(*), min(g.geoid)::text
                       FROM tgsis.geometry g
                      WHERE g.geoid = ANY (v_geo.geoids) AND g.geotype = 'GEOMETRYCOLLECTION'
                     HAVING count(*) > 0;
        RETURN QUERY SELECT 'owned member not listed in geoids'::text, count(*), min(g.geoid)::text
                       FROM tgsis.geometry g
                      WHERE g.collection = p_geoid AND NOT g.geoid = ANY (v_geo.geoids)
                     HAVING count(*) > 0;
        RETURN QUERY
            SELECT 'bounding box or counts out of date (run tgsis.refresh_geometry)'::text, 1::bigint, NULL::text
              FROM (SELECT coalesce(sum(g.nvrtx), 0) AS n, coalesce(sum(g.ncell), 0) AS m,
                           CASE WHEN count(g.bbox) > 0 THEN
                               cube(ARRAY[min(cube_ll_coord(g.bbox, 1)), min(cube_ll_coord(g.bbox, 2)), min(cube_ll_coord(g.bbox, 3))],
                                    ARRAY[max(cube_ur_coord(g.bbox, 1)), max(cube_ur_coord(g.bbox, 2)), max(cube_ur_coord(g.bbox, 3))])
                           END AS bbox
                      FROM tgsis.geometry g WHERE g.geoid = ANY (v_geo.geoids)) AS u
             WHERE u.n <> v_geo.nvrtx OR u.m <> v_geo.ncell OR u.bbox IS DISTINCT FROM v_geo.bbox;
        RETURN;
    END IF;

    -- the rest is the data model's (tgsis.data_models.check_function)
    SELECT m.check_function INTO v_hook FROM tgsis.data_models m WHERE m.timemodel = v_geo.timemodel;
    RETURN QUERY EXECUTE format('SELECT c.problem, c.count, c.example FROM tgsis.%I($1) c', v_hook) USING p_geoid;
END
$$;

COMMENT ON FUNCTION tgsis.check_geometry(bigint) IS
    'problems of a stored geometry: missing, nested or unlisted members and stale bbox/counts of a collection; the others by their data model''s check function (tgsis.data_models: tgsis.check_static_geometry, tgsis.check_temporal_geometry)';

-- ==== versioning/revision_seq.sql ====
-- The one sequence every revision number comes from. Revision 0 is DEFAULT's
-- initial revision (inserted with the schema); the sequence starts at 1.
CREATE SEQUENCE tgsis.revision_seq AS integer START WITH 1 MINVALUE 1;

COMMENT ON SEQUENCE tgsis.revision_seq IS
    'revision numbers: one sequence for all versions, so a revision number names exactly one version';

-- ==== versioning/versions.sql ====
-- The version tree. DEFAULT (versionid 0) is the root; every other version has
-- one parent. workingset is the working revision set (ascending): the
-- parent's set at initrevision plus the version's own revisions since its
-- base; merge and refresh move the base. Reads need one indexed lookup.
CREATE TABLE tgsis.versions (
    versionid       integer     GENERATED BY DEFAULT AS IDENTITY (START WITH 1) PRIMARY KEY,
    name            text        NOT NULL UNIQUE,
    parentid        integer     REFERENCES tgsis.versions (versionid),
    initrevision    integer,
    workingrevision integer     NOT NULL,
    workingset      integer[]   NOT NULL,
    owner           name        NOT NULL DEFAULT current_user,
    description     text,
    created_at      timestamptz NOT NULL DEFAULT now(),
    valid_from      timestamptz,
    valid_to        timestamptz,
    CONSTRAINT versions_validity CHECK (valid_to IS NULL OR (valid_from IS NOT NULL AND valid_to > valid_from)),
    CONSTRAINT versions_root CHECK ((versionid = 0) = (parentid IS NULL) AND (parentid IS NULL) = (initrevision IS NULL)),
    CONSTRAINT versions_not_own_parent CHECK (parentid <> versionid),
    CONSTRAINT versions_working_in_set CHECK (workingrevision = workingset[cardinality(workingset)])
);

CREATE INDEX versions_parentid_idx ON tgsis.versions (parentid);

COMMENT ON SEQUENCE tgsis.versions_versionid_seq IS 'version ids (identity of tgsis.versions; DEFAULT is 0)';
COMMENT ON TABLE tgsis.versions IS 'versions (long transactions): a tree rooted at DEFAULT';
COMMENT ON COLUMN tgsis.versions.versionid IS 'version id (0: DEFAULT)';
COMMENT ON COLUMN tgsis.versions.name IS 'version name, unique; DEFAULT is the root';
COMMENT ON COLUMN tgsis.versions.parentid IS 'parent version (NULL only for DEFAULT)';
COMMENT ON COLUMN tgsis.versions.initrevision IS 'the parent''s revision this version is based on: its working revision at creation, or at the last merge or refresh (NULL for DEFAULT)';
COMMENT ON COLUMN tgsis.versions.workingrevision IS 'the revision changes made in this version are labelled with (its largest revision)';
COMMENT ON COLUMN tgsis.versions.workingset IS
    'working revision set, ascending: the parent''s set at initrevision plus the version''s own revisions since its base';
COMMENT ON COLUMN tgsis.versions.owner IS 'role that created the version';
COMMENT ON COLUMN tgsis.versions.description IS 'free text';
COMMENT ON COLUMN tgsis.versions.created_at IS 'when the version was created';
COMMENT ON COLUMN tgsis.versions.valid_from IS 'start of the period in which the version was believed true (NULL: no validity period)';
COMMENT ON COLUMN tgsis.versions.valid_to IS 'end of that period, exclusive (NULL: still believed)';

-- ==== versioning/revisions.sql ====
-- Every revision and the version it belongs to. A revision is writable only
-- while it is its version's working revision; a named (saved) revision is
-- frozen for good.
CREATE TABLE tgsis.revisions (
    revision   integer     PRIMARY KEY CHECK (revision >= 0),
    versionid  integer     NOT NULL REFERENCES tgsis.versions (versionid) ON DELETE CASCADE,
    name       text,
    created_at timestamptz NOT NULL DEFAULT now(),
    created_by name        NOT NULL DEFAULT current_user,
    saved_at   timestamptz,
    visibleset integer[],
    UNIQUE (versionid, name),
    CONSTRAINT revisions_saved_named CHECK ((name IS NULL) = (saved_at IS NULL))
);

CREATE INDEX revisions_versionid_idx ON tgsis.revisions (versionid, revision);

COMMENT ON TABLE tgsis.revisions IS 'revisions: integer labels of groups of changes, each owned by one version';
COMMENT ON COLUMN tgsis.revisions.revision IS 'revision number (0: DEFAULT''s initial revision; others from tgsis.revision_seq)';
COMMENT ON COLUMN tgsis.revisions.versionid IS 'the version it belongs to';
COMMENT ON COLUMN tgsis.revisions.name IS 'name given by save_revision (NULL: not saved); unique within the version';
COMMENT ON COLUMN tgsis.revisions.created_at IS 'when the revision was handed out';
COMMENT ON COLUMN tgsis.revisions.created_by IS 'role whose call handed it out';
COMMENT ON COLUMN tgsis.revisions.saved_at IS 'when save_revision froze it (NULL: not saved)';
COMMENT ON COLUMN tgsis.revisions.visibleset IS
    'the revision set its version saw while it was the working revision, stored when it stopped being one (NULL while working): what goto_revision shows';

-- ==== versioning/default_version.sql ====
-- The root version DEFAULT with its initial revision 0, created with the schema.
INSERT INTO tgsis.versions (versionid, name, parentid, initrevision, workingrevision, workingset, description)
VALUES (0, 'DEFAULT', NULL, NULL, 0, '{0}', 'the root version');
INSERT INTO tgsis.revisions (revision, versionid) VALUES (0, 0);

-- ==== versioning/versioned_tables.sql ====
-- Tables registered for versioning (the thesis' VERSIONEDTABLE). A registered
-- table <t> is stored in <t>_ver and read and written through the view <t>.
CREATE TABLE tgsis.versioned_tables (
    schemaname          text     NOT NULL,
    tablename           text     NOT NULL,
    shortname           text     NOT NULL,
    objectkeyfield      text     NOT NULL,
    objectclass         text     NOT NULL,
    iudorder            integer  NOT NULL,
    keycolumns          text[]   NOT NULL,
    pkeyname            text     NOT NULL,
    tablecomment        text,
    identity_always     text[]   NOT NULL DEFAULT '{}',
    enabled_at          timestamptz NOT NULL DEFAULT now(),
    enabled_by          name     NOT NULL DEFAULT current_user,
    PRIMARY KEY (schemaname, tablename),
    UNIQUE (objectclass, shortname)
);

COMMENT ON TABLE tgsis.versioned_tables IS
    'tables registered for versioning: <tablename> is now a view over <tablename>_ver with INSTEAD OF triggers';
COMMENT ON COLUMN tgsis.versioned_tables.schemaname IS 'schema of the table, its _ver storage and its view';
COMMENT ON COLUMN tgsis.versioned_tables.tablename IS 'original table name, now the name of the view';
COMMENT ON COLUMN tgsis.versioned_tables.shortname IS 'short name used in conflict reports (unique within the object class)';
COMMENT ON COLUMN tgsis.versioned_tables.objectkeyfield IS 'column holding the key of the object a row belongs to';
COMMENT ON COLUMN tgsis.versioned_tables.objectclass IS 'object class: the tables that together store one kind of object';
COMMENT ON COLUMN tgsis.versioned_tables.iudorder IS 'order in which a merge applies the class''s tables (ascending for inserts/updates)';
COMMENT ON COLUMN tgsis.versioned_tables.keycolumns IS 'primary-key columns of the original table (the row key)';
COMMENT ON COLUMN tgsis.versioned_tables.pkeyname IS 'name of the original primary-key constraint (reported by duplicate-key errors, restored on disable)';
COMMENT ON COLUMN tgsis.versioned_tables.tablecomment IS 'the table''s comment before versioning (restored by disable_versioning)';
COMMENT ON COLUMN tgsis.versioned_tables.identity_always IS 'GENERATED ALWAYS identity columns turned BY DEFAULT in _ver (restored on disable)';
COMMENT ON COLUMN tgsis.versioned_tables.enabled_at IS 'when versioning was enabled';
COMMENT ON COLUMN tgsis.versioned_tables.enabled_by IS 'role that enabled it';

-- ==== versioning/versioning_dropped.sql ====
-- Constraints and unique indexes that enable_versioning dropped because they
-- cannot hold across versions; disable_versioning restores each one as soon
-- as the tables it involves are plain tables again.
CREATE TABLE tgsis.versioning_dropped (
    id          integer GENERATED ALWAYS AS IDENTITY PRIMARY KEY,
    schemaname  text    NOT NULL,
    tablename   text    NOT NULL,
    name        text    NOT NULL,
    definition  text    NOT NULL,
    is_index    boolean NOT NULL DEFAULT false,
    refschema   text,
    reftable    text,
    dropped_for text    NOT NULL,
    dropped_at  timestamptz NOT NULL DEFAULT now()
);

COMMENT ON SEQUENCE tgsis.versioning_dropped_id_seq IS 'row ids of tgsis.versioning_dropped';
COMMENT ON TABLE tgsis.versioning_dropped IS
    'constraints and unique indexes dropped by enable_versioning (they cannot hold across versions), restored by disable_versioning';
COMMENT ON COLUMN tgsis.versioning_dropped.id IS 'row id';
COMMENT ON COLUMN tgsis.versioning_dropped.schemaname IS 'schema of the table that carried the constraint';
COMMENT ON COLUMN tgsis.versioning_dropped.tablename IS 'table that carried the constraint (its plain name)';
COMMENT ON COLUMN tgsis.versioning_dropped.name IS 'constraint or index name';
COMMENT ON COLUMN tgsis.versioning_dropped.definition IS 'pg_get_constraintdef / pg_get_indexdef text';
COMMENT ON COLUMN tgsis.versioning_dropped.is_index IS 'true: a unique index (definition is a CREATE INDEX statement)';
COMMENT ON COLUMN tgsis.versioning_dropped.refschema IS 'schema of the referenced table of a foreign key';
COMMENT ON COLUMN tgsis.versioning_dropped.reftable IS 'referenced table of a foreign key';
COMMENT ON COLUMN tgsis.versioning_dropped.dropped_for IS 'the table whose versioning dropped it';
COMMENT ON COLUMN tgsis.versioning_dropped.dropped_at IS 'when it was dropped';

-- ==== core/catalog.sql ====
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

-- ==== core/class_tables.sql ====
-- tgsis.class_tables: every table of every feature class, one row each, in creation order.
-- A class has a feature table, a cell-property table, possibly a table of the
-- properties of its other alignment and, if temporal, a per-instant property
-- table (tgsis.catalog names them in four columns). Versioning, deletion and
-- the checks of what may be versioned read this view instead of naming the
-- four columns each, so a table a class gains later is added here once.
CREATE VIEW tgsis.class_tables AS
SELECT c.classname, c.schemaname, t.tablename, t.kind, t.position
  FROM tgsis.catalog c
 CROSS JOIN LATERAL (VALUES (c.featuretable, 'feature', 1),
                            (c.cellprotable, 'cell', 2),
                            (c.otherprotable, 'other', 3),
                            (c.protablename, 'instant', 4)) AS t (tablename, kind, position)
 WHERE t.tablename IS NOT NULL;

COMMENT ON VIEW tgsis.class_tables IS
    'the tables of each feature class (tgsis.catalog): feature (one row per feature), cell (cell or vertex properties), other (properties of the other alignment), instant (per-instant properties of temporal classes), keyed by _geoid';
COMMENT ON COLUMN tgsis.class_tables.classname IS 'the feature class (tgsis.catalog.classname)';
COMMENT ON COLUMN tgsis.class_tables.schemaname IS 'schema of the table';
COMMENT ON COLUMN tgsis.class_tables.tablename IS 'the table';
COMMENT ON COLUMN tgsis.class_tables.kind IS 'feature, cell, other or instant';
COMMENT ON COLUMN tgsis.class_tables.position IS 'creation order within the class: 1 feature, 2 cell, 3 other, 4 instant (children after the feature table)';

-- ==== versioning/check_version_name.sql ====
-- tgsis.check_version_name(name, what): raise TG101 unless the name is a usable version or revision name.
CREATE FUNCTION tgsis.check_version_name(p_name text, p_what text DEFAULT 'version')
RETURNS text
LANGUAGE plpgsql
IMMUTABLE
PARALLEL SAFE
AS $$
BEGIN
    IF p_name IS NULL OR p_name !~ '^[[:alnum:]_][[:alnum:]_.+-]{0,62}$' THEN
        RAISE EXCEPTION '% name % is not allowed', p_what, coalesce(quote_literal(p_name), 'NULL')
            USING ERRCODE = 'TG101',
                  DETAIL = 'Names are 1 to 63 characters: letters, digits and _ . + -, not starting with . + or -. (@ is kept for VERSION@REVISION on the command line.)';
    END IF;
    RETURN p_name;
END
$$;

COMMENT ON FUNCTION tgsis.check_version_name(text, text) IS
    'returns the name when it is a valid version or revision name (1-63 letters, digits, _ . + -), else raises TG101';

-- ==== versioning/version_id.sql ====
-- tgsis.version_id(name): id of a version, or TG200 naming it.
CREATE FUNCTION tgsis.version_id(p_name text)
RETURNS integer
LANGUAGE plpgsql
STABLE
AS $$
DECLARE
    v_id integer;
BEGIN
    SELECT versionid INTO v_id FROM tgsis.versions WHERE name = p_name;
    IF NOT FOUND THEN
        RAISE EXCEPTION 'version % does not exist', coalesce(quote_literal(p_name), 'NULL')
            USING ERRCODE = 'TG200', HINT = 'SELECT name FROM tgsis.versions lists the versions';
    END IF;
    RETURN v_id;
END
$$;

COMMENT ON FUNCTION tgsis.version_id(text) IS 'id of the version with that name; raises TG200 when there is none';

-- ==== versioning/object_lock_key.sql ====
-- tgsis.object_lock_key(objectclass, key, versionid): the advisory lock key of one object in one version.
-- Writes through versioned views hold it shared for their transaction, the
-- bulk writers of an object (check-in, save by difference, set-based
-- deletes) exclusively (tgsis.object_write_lock): a bulk writer decides from
-- the object's state with no view writer of it in flight, and a view writer
-- that comes later finds its state changed. Writers of the object in other
-- versions do not wait for each other: the version is the hash's seed.
CREATE FUNCTION tgsis.object_lock_key(p_objectclass text, p_key text, p_versionid integer)
RETURNS bigint
LANGUAGE sql
IMMUTABLE
PARALLEL SAFE
AS $$
    SELECT pg_catalog.hashtextextended(p_objectclass || ':' || p_key, p_versionid)
$$;

COMMENT ON FUNCTION tgsis.object_lock_key(text, text, integer) IS
    'advisory lock key (64-bit hash) of object p_key of a class in a version: held shared by view writes, exclusively by bulk writers of the object';

-- ==== versioning/version_privileges.sql ====
-- Rights on versions beyond ownership. A version's owner (the role that
-- created it) and members of tgsis_admin hold every right on it; other roles
-- hold what is granted here, to them or to a role they are members of
-- ('public': everybody). DEFAULT starts writable by tgsis_editor, who may
-- also create children of it; merging into DEFAULT is left to tgsis_admin.
CREATE TABLE tgsis.version_privileges (
    versionid  integer     NOT NULL REFERENCES tgsis.versions (versionid) ON DELETE CASCADE,
    grantee    name        NOT NULL,
    privilege  text        NOT NULL CHECK (privilege IN ('write', 'create', 'merge', 'delete')),
    granted_by name        NOT NULL,
    granted_at timestamptz NOT NULL DEFAULT now(),
    PRIMARY KEY (versionid, grantee, privilege)
);

INSERT INTO tgsis.version_privileges (versionid, grantee, privilege, granted_by)
VALUES (0, 'tgsis_editor', 'write', current_user), (0, 'tgsis_editor', 'create', current_user);

COMMENT ON TABLE tgsis.version_privileges IS
    'rights on versions granted to roles other than the version''s owner and tgsis_admin (who hold them all)';
COMMENT ON COLUMN tgsis.version_privileges.versionid IS 'the version';
COMMENT ON COLUMN tgsis.version_privileges.grantee IS 'role granted the right (its members have it too); public: every role';
COMMENT ON COLUMN tgsis.version_privileges.privilege IS
    'write: change rows, save revisions, resolve conflicts, refresh, lock objects; create: create child versions; merge: merge a child into this version; delete: delete this version';
COMMENT ON COLUMN tgsis.version_privileges.granted_by IS 'role that granted it';
COMMENT ON COLUMN tgsis.version_privileges.granted_at IS 'when it was granted';

-- ==== versioning/calling_role.sql ====
-- tgsis.calling_role(): the role a session acts as, also inside SECURITY DEFINER functions.
-- There current_user is the function's owner; the session's role is the one
-- SET ROLE chose (the role setting), or else the role that logged in. Both
-- can only be roles the login may act as, so the answer cannot be forged.
CREATE FUNCTION tgsis.calling_role()
RETURNS name
LANGUAGE sql
STABLE
PARALLEL SAFE
AS $$
    SELECT CASE WHEN pg_catalog.current_setting('role') = 'none' THEN session_user
                ELSE pg_catalog.current_setting('role')::name END
$$;

COMMENT ON FUNCTION tgsis.calling_role() IS
    'the role the session acts as (SET ROLE''s role, else the login role), also inside SECURITY DEFINER functions: whose version rights are checked';

-- ==== versioning/is_version_owner.sql ====
-- tgsis.is_version_owner(versionid, role): whether a role owns a version in the sense of its rights.
-- The owner of the version or of any ancestor (whoever owns a version
-- manages the versions made below it), roles using their rights (members),
-- tgsis_admin members and superusers (pg_has_role is true for them).
-- PL/pgSQL, not SQL: the write triggers ask once per row, and PL/pgSQL keeps
-- its plans for the session where a SQL function would be planned per call.
CREATE FUNCTION tgsis.is_version_owner(p_versionid integer, p_role name)
RETURNS boolean
LANGUAGE plpgsql
STABLE
AS $$
DECLARE
    v_owner  name;
    v_parent integer := p_versionid;
BEGIN
    IF pg_catalog.pg_has_role(p_role, 'tgsis_admin', 'USAGE') THEN
        RETURN true;
    END IF;
    WHILE v_parent IS NOT NULL LOOP
        SELECT owner, parentid INTO v_owner, v_parent FROM tgsis.versions WHERE versionid = v_parent;
        IF v_owner = p_role
           OR (EXISTS (SELECT FROM pg_catalog.pg_roles WHERE rolname = v_owner)
               AND pg_catalog.pg_has_role(p_role, v_owner, 'USAGE')) THEN
            RETURN true;
        END IF;
    END LOOP;
    RETURN false;
END
$$;

COMMENT ON FUNCTION tgsis.is_version_owner(integer, name) IS
    'whether a role holds every right on a version: owner (or member of the owner) of it or of an ancestor, a tgsis_admin, or a superuser';

-- ==== versioning/holds_version_privilege.sql ====
-- tgsis.holds_version_privilege(versionid, privilege, role): the rule behind has_version_privilege, for callers that checked their arguments.
-- Ownership (tgsis.is_version_owner) or a grant to public or to a role
-- whose rights p_role uses.
CREATE FUNCTION tgsis.holds_version_privilege(p_versionid integer, p_privilege text, p_role name)
RETURNS boolean
LANGUAGE plpgsql
STABLE
AS $$
BEGIN
    RETURN EXISTS (SELECT FROM tgsis.version_privileges p LEFT JOIN pg_catalog.pg_roles r ON r.rolname = p.grantee
                    WHERE p.versionid = p_versionid AND p.privilege = p_privilege
                      AND (p.grantee = 'public' OR (r.oid IS NOT NULL AND pg_catalog.pg_has_role(p_role, r.oid, 'USAGE'))))
        OR tgsis.is_version_owner(p_versionid, p_role);
END
$$;

COMMENT ON FUNCTION tgsis.holds_version_privilege(integer, text, name) IS
    'whether p_role holds p_privilege on a version (owner, ancestor owner, tgsis_admin, or a grant); arguments unchecked: use tgsis.has_version_privilege';

-- ==== versioning/version_privilege_list.sql ====
-- tgsis.version_privilege_list(privilege): the rights a privilege name stands for, checked; 'all' is all four.
CREATE FUNCTION tgsis.version_privilege_list(p_privilege text)
RETURNS text[]
LANGUAGE plpgsql
IMMUTABLE
AS $$
BEGIN
    IF lower(p_privilege) = 'all' THEN
        RETURN ARRAY['write', 'create', 'merge', 'delete'];
    ELSIF p_privilege IS NULL OR lower(p_privilege) NOT IN ('write', 'create', 'merge', 'delete') THEN
        RAISE EXCEPTION 'unknown version privilege %', coalesce(quote_literal(p_privilege), 'NULL')
            USING ERRCODE = 'TG100', HINT = 'version privileges: write, create, merge, delete, or all';
    END IF;
    RETURN ARRAY[lower(p_privilege)];
END
$$;

COMMENT ON FUNCTION tgsis.version_privilege_list(text) IS
    'the version rights named by p_privilege (write, create, merge, delete, or all for the four); TG100 for any other name';

-- ==== versioning/check_role.sql ====
-- tgsis.check_role(role, allow_public): TG200 unless the role exists (or, when allowed, is public).
CREATE FUNCTION tgsis.check_role(p_role text, p_allow_public boolean DEFAULT false)
RETURNS void
LANGUAGE plpgsql
STABLE
AS $$
BEGIN
    IF p_role IS NULL
       OR NOT ((p_allow_public AND p_role = 'public') OR EXISTS (SELECT FROM pg_catalog.pg_roles WHERE rolname = p_role)) THEN
        RAISE EXCEPTION 'role % does not exist', coalesce(quote_literal(p_role), 'NULL')
            USING ERRCODE = 'TG200',
                  HINT = CASE WHEN p_allow_public THEN 'name an existing role, or public for every role'
                              ELSE 'name an existing role' END;
    END IF;
END
$$;

COMMENT ON FUNCTION tgsis.check_role(text, boolean) IS
    'raise TG200 naming the role unless it exists (or p_allow_public and it is public)';

-- ==== versioning/has_version_privilege.sql ====
-- tgsis.has_version_privilege(version, privilege, role): whether a role holds a right on a version.
-- Superusers, members of tgsis_admin and owners of the version or of an
-- ancestor hold them all;
-- otherwise a grant in tgsis.version_privileges to public or to a role whose
-- rights the role uses (pg_has_role USAGE, as for table privileges).
CREATE FUNCTION tgsis.has_version_privilege(p_version text, p_privilege text, p_role name DEFAULT NULL)
RETURNS boolean
LANGUAGE plpgsql
STABLE
SECURITY DEFINER
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_role    name := coalesce(p_role, tgsis.calling_role());
    v_version tgsis.versions;
    v_wanted  text[] := tgsis.version_privilege_list(p_privilege);
BEGIN
    PERFORM tgsis.check_role(v_role);
    SELECT * INTO v_version FROM tgsis.versions WHERE versionid = tgsis.version_id(p_version);
    RETURN (SELECT bool_and(tgsis.holds_version_privilege(v_version.versionid, p, v_role)) FROM unnest(v_wanted) AS p);
END
$$;

COMMENT ON FUNCTION tgsis.has_version_privilege(text, text, name) IS
    'whether a role (default: the calling role) holds a right (write, create, merge, delete; all: the four) on a version: as its owner, as a tgsis_admin, or by a grant';

-- ==== versioning/require_version_privilege.sql ====
-- tgsis.require_version_privilege(versionid, privilege, doing): TG002 unless the calling role holds the right.
-- p_doing says what was refused ("merge into", "delete", ...) for the message.
-- Called by the SECURITY DEFINER version functions (and, through
-- write_revision, once per row by the write triggers): no SET clause of its
-- own, which would cost a configuration change per call.
CREATE FUNCTION tgsis.require_version_privilege(p_versionid integer, p_privilege text, p_doing text)
RETURNS void
LANGUAGE plpgsql
STABLE
AS $$
DECLARE
    v_version tgsis.versions;
    v_role    name := tgsis.calling_role();
BEGIN
    IF tgsis.holds_version_privilege(p_versionid, p_privilege, v_role) THEN
        RETURN;
    END IF;
    SELECT * INTO v_version FROM tgsis.versions WHERE versionid = p_versionid;
    RAISE EXCEPTION 'role % may not % version %', quote_ident(v_role), p_doing, quote_literal(v_version.name)
        USING ERRCODE = 'TG002',
              DETAIL = format('That needs the %s right on %s, held by its owner %s, by tgsis_admin and by the roles it was granted to.',
                              lower(p_privilege), v_version.name, quote_ident(v_version.owner)),
              HINT = format('the owner or a tgsis_admin can run SELECT tgsis.grant_version(%L, %L, %L)',
                            v_version.name, lower(p_privilege), v_role);
END
$$;

COMMENT ON FUNCTION tgsis.require_version_privilege(integer, text, text) IS
    'raise TG002 (naming the role, the action and the version) unless the calling role holds the right on the version';

-- ==== versioning/require_version_owner.sql ====
-- tgsis.require_version_owner(versionid, doing): TG002 unless the calling role owns the version or is a tgsis_admin.
-- For what only an owner may do: grant and revoke rights, change the owner,
-- set the validity period.
CREATE FUNCTION tgsis.require_version_owner(p_versionid integer, p_doing text)
RETURNS void
LANGUAGE plpgsql
STABLE
AS $$
DECLARE
    v_version tgsis.versions;
    v_role    name := tgsis.calling_role();
BEGIN
    SELECT * INTO v_version FROM tgsis.versions WHERE versionid = p_versionid;
    IF NOT tgsis.is_version_owner(p_versionid, v_role) THEN
        RAISE EXCEPTION 'role % may not % version %', quote_ident(v_role), p_doing, quote_literal(v_version.name)
            USING ERRCODE = 'TG002',
                  DETAIL = format('Only its owner %s, the owners of its ancestors and tgsis_admin may.', quote_ident(v_version.owner));
    END IF;
END
$$;

COMMENT ON FUNCTION tgsis.require_version_owner(integer, text) IS
    'raise TG002 unless the calling role is (a member of) the version''s owner or a tgsis_admin';

-- ==== versioning/grant_version.sql ====
-- tgsis.grant_version(version, privilege, role): give a role (or public) a right on a version; owner or tgsis_admin only.
CREATE FUNCTION tgsis.grant_version(p_version text, p_privilege text, p_role text)
RETURNS void
LANGUAGE plpgsql
VOLATILE
SECURITY DEFINER
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_id integer := tgsis.version_id(p_version);
BEGIN
    PERFORM tgsis.require_version_owner(v_id, 'grant rights on');
    PERFORM tgsis.check_role(p_role, true);
    INSERT INTO tgsis.version_privileges (versionid, grantee, privilege, granted_by)
    SELECT v_id, p_role, p, tgsis.calling_role() FROM unnest(tgsis.version_privilege_list(p_privilege)) AS p
        ON CONFLICT DO NOTHING;
END
$$;

COMMENT ON FUNCTION tgsis.grant_version(text, text, text) IS
    'grant a right on a version (write, create, merge, delete or all) to a role or public; only its owner or a tgsis_admin may';

-- ==== versioning/revoke_version.sql ====
-- tgsis.revoke_version(version, privilege, role): take back a granted right; owner or tgsis_admin only.
-- Ownership and tgsis_admin membership are not grants and stay.
CREATE FUNCTION tgsis.revoke_version(p_version text, p_privilege text, p_role text)
RETURNS void
LANGUAGE plpgsql
VOLATILE
SECURITY DEFINER
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_id integer := tgsis.version_id(p_version);
BEGIN
    PERFORM tgsis.require_version_owner(v_id, 'revoke rights on');
    PERFORM tgsis.check_role(p_role, true);
    DELETE FROM tgsis.version_privileges
     WHERE versionid = v_id AND grantee = p_role AND privilege = ANY (tgsis.version_privilege_list(p_privilege));
END
$$;

COMMENT ON FUNCTION tgsis.revoke_version(text, text, text) IS
    'revoke a granted right on a version (write, create, merge, delete or all) from a role or public; only its owner or a tgsis_admin may';

-- ==== versioning/set_version_owner.sql ====
-- tgsis.set_version_owner(version, role): hand a version to another role; owner or tgsis_admin only.
CREATE FUNCTION tgsis.set_version_owner(p_version text, p_role text)
RETURNS void
LANGUAGE plpgsql
VOLATILE
SECURITY DEFINER
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_id integer := tgsis.version_id(p_version);
BEGIN
    PERFORM tgsis.require_version_owner(v_id, 'change the owner of');
    PERFORM tgsis.check_role(p_role);
    UPDATE tgsis.versions SET owner = p_role WHERE versionid = v_id;
END
$$;

COMMENT ON FUNCTION tgsis.set_version_owner(text, text) IS
    'make a role the owner of a version (it then holds every right on it); only the owner or a tgsis_admin may';

-- ==== versioning/get_working_version.sql ====
-- tgsis.get_working_version(): name of the session's working version (setting tgsis.version; DEFAULT when unset).
CREATE FUNCTION tgsis.get_working_version()
RETURNS text
LANGUAGE sql
STABLE
PARALLEL SAFE
AS $$
    SELECT coalesce(nullif(current_setting('tgsis.version', true), ''), 'DEFAULT')
$$;

COMMENT ON FUNCTION tgsis.get_working_version() IS
    'name of the session''s working version: the setting tgsis.version (set by goto_version, or SET [LOCAL] tgsis.version), DEFAULT when unset';

-- ==== versioning/object_write_lock.sql ====
-- tgsis.object_write_lock(objectclass, keys): lock objects of the session's version for a bulk write until the transaction ends.
-- Exclusive, in key order (two bulk writers of the same objects cannot
-- deadlock). It waits for the transactions that wrote rows of these objects
-- through the versioned views (they hold tgsis.object_lock_key shared), and
-- such writes wait for it: check-in, save by difference and set-based
-- deletes then read the object's state, decide and write with no
-- concurrent change in between (no lost update, no resurrected row).
CREATE FUNCTION tgsis.object_write_lock(p_objectclass text, p_keys text[])
RETURNS void
LANGUAGE plpgsql
VOLATILE
AS $$
DECLARE
    v_versionid integer := tgsis.version_id(tgsis.get_working_version());
BEGIN
    PERFORM pg_catalog.pg_advisory_xact_lock(tgsis.object_lock_key(p_objectclass, k, v_versionid))
       FROM (SELECT DISTINCT k FROM unnest(p_keys) AS u(k) WHERE k IS NOT NULL ORDER BY k) AS s;
END
$$;

COMMENT ON FUNCTION tgsis.object_write_lock(text, text[]) IS
    'take the exclusive object write locks (tgsis.object_lock_key) of objects of a class in the session''s version, in key order, until the transaction ends: waits for open view writers of them, who then wait for it';

-- ==== versioning/require_read_committed.sql ====
-- tgsis.require_read_committed(action): TG300 unless the transaction is READ COMMITTED.
-- Merge, refresh, set-based deletes and the check-in's check lock what they
-- work on (the versions' rows, the objects' write locks) and then read the
-- rows with statements that must see everything committed by the writers they
-- waited for. In READ COMMITTED every statement takes a new snapshot; in
-- REPEATABLE READ and SERIALIZABLE the snapshot is the transaction's first
-- one, and rows committed while they waited would be missed (a merge would
-- then move the version's base past changes it did not copy).
CREATE FUNCTION tgsis.require_read_committed(p_action text)
RETURNS void
LANGUAGE plpgsql
STABLE
AS $$
BEGIN
    IF current_setting('transaction_isolation') <> 'read committed' THEN
        RAISE EXCEPTION '% cannot run in a % transaction', p_action, upper(current_setting('transaction_isolation'))
            USING ERRCODE = 'TG300',
                  DETAIL = 'It waits for concurrent writers and must then see what they committed; the transaction''s '
                           'snapshot is older than that.',
                  HINT = 'run it in a READ COMMITTED transaction (PostgreSQL''s default)';
    END IF;
END
$$;

COMMENT ON FUNCTION tgsis.require_read_committed(text) IS
    'raise TG300 naming the action unless the transaction''s isolation level is READ COMMITTED (merge, refresh, set-based deletes, check-in checks must see what the writers they waited for committed)';

-- ==== versioning/get_viewing_revision.sql ====
-- tgsis.get_viewing_revision(): the older revision the session looks at (setting tgsis.revision), NULL for none.
CREATE FUNCTION tgsis.get_viewing_revision()
RETURNS integer
LANGUAGE plpgsql
STABLE
PARALLEL SAFE
AS $$
DECLARE
    v_text text := nullif(btrim(current_setting('tgsis.revision', true)), '');
BEGIN
    IF v_text IS NULL THEN
        RETURN NULL;
    END IF;
    IF v_text !~ '^[0-9]{1,9}$' THEN
        RAISE EXCEPTION 'setting tgsis.revision is %, not a revision number', quote_literal(v_text)
            USING ERRCODE = 'TG100', HINT = 'SELECT tgsis.goto_version(tgsis.get_working_version()) clears it';
    END IF;
    RETURN v_text::integer;
END
$$;

COMMENT ON FUNCTION tgsis.get_viewing_revision() IS
    'the revision the session views instead of its working revision (setting tgsis.revision, set by goto_revision); NULL when none';

-- ==== versioning/revision_set.sql ====
-- tgsis.revision_set(versionid, revision): the revision set of (version, revision), or TG200 when the revision is not in its history.
-- The working revision sees the version's working set; any other revision of
-- its history sees what its version saw while it was working (stored when it
-- was frozen). The history is the working set plus the version's own older
-- revisions (merge and refresh move a version's base, not its past).
CREATE FUNCTION tgsis.revision_set(p_versionid integer, p_revision integer)
RETURNS integer[]
LANGUAGE plpgsql
STABLE
SECURITY DEFINER
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_version tgsis.versions;
    v_set     integer[];
BEGIN
    SELECT * INTO v_version FROM tgsis.versions WHERE versionid = p_versionid;
    IF p_revision IS NULL OR p_revision = v_version.workingrevision THEN
        RETURN v_version.workingset;
    END IF;
    SELECT r.visibleset INTO v_set FROM tgsis.revisions r
     WHERE r.revision = p_revision AND (r.revision = ANY (v_version.workingset) OR r.versionid = p_versionid);
    IF v_set IS NULL THEN
        RAISE EXCEPTION 'revision % is not in the history of version %', p_revision, quote_literal(v_version.name)
            USING ERRCODE = 'TG200',
                  DETAIL = format('Version %s can look at revisions %s.', v_version.name,
                                  (SELECT string_agg(h.revision::text, ', ' ORDER BY h.revision) FROM tgsis.revisions h
                                    WHERE h.revision = ANY (v_version.workingset) OR h.versionid = p_versionid)),
                  HINT = 'a version sees its own revisions and its ancestors'' revisions up to the moment it was based on them';
    END IF;
    RETURN v_set;
END
$$;

COMMENT ON FUNCTION tgsis.revision_set(integer, integer) IS
    'revision set of (version, revision): the working set for the working revision, the stored set of a frozen revision of its history; TG200 otherwise';

-- ==== versioning/get_revisions.sql ====
-- tgsis.get_revisions(viewing): the session's viewing revision set (true) or working revision set (false).
-- Versioned views call it once per query (as a scalar subquery), so it is
-- one indexed lookup. SECURITY DEFINER: roles that may read a versioned view
-- need not read the version tables themselves.
CREATE FUNCTION tgsis.get_revisions(p_viewing boolean DEFAULT true)
RETURNS integer[]
LANGUAGE plpgsql
STABLE
SECURITY DEFINER
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_name     text := tgsis.get_working_version();
    v_working  integer;
    v_set      integer[];
    v_viewing  integer;
BEGIN
    SELECT workingrevision, workingset INTO v_working, v_set FROM tgsis.versions WHERE name = v_name;
    IF NOT FOUND THEN
        RAISE EXCEPTION 'version % does not exist', quote_literal(v_name)
            USING ERRCODE = 'TG200',
                  DETAIL = 'The session''s working version (setting tgsis.version) names no version.',
                  HINT = 'SELECT tgsis.goto_version(''DEFAULT''); SELECT name FROM tgsis.versions lists the versions';
    END IF;
    IF NOT coalesce(p_viewing, true) THEN
        RETURN v_set;
    END IF;
    v_viewing := tgsis.get_viewing_revision();
    IF v_viewing IS NULL OR v_viewing = v_working THEN
        RETURN v_set;
    END IF;
    RETURN tgsis.revision_set((SELECT versionid FROM tgsis.versions WHERE name = v_name), v_viewing);
END
$$;

COMMENT ON FUNCTION tgsis.get_revisions(boolean) IS
    'the session''s viewing revision set (true, what queries see) or working revision set (false, what changes see), ascending';

-- ==== versioning/get_working_revision.sql ====
-- tgsis.get_working_revision(): the working revision of the session's working version.
CREATE FUNCTION tgsis.get_working_revision()
RETURNS integer
LANGUAGE sql
STABLE
AS $$
    SELECT s[cardinality(s)] FROM (SELECT tgsis.get_revisions(false)) AS w(s)
$$;

COMMENT ON FUNCTION tgsis.get_working_revision() IS
    'the working revision of the session''s working version: the revision its changes are labelled with';

-- ==== versioning/goto_version.sql ====
-- tgsis.goto_version(name, local): make a version the session's (or, with local, the transaction's) working version.
CREATE FUNCTION tgsis.goto_version(p_name text, p_local boolean DEFAULT false)
RETURNS text
LANGUAGE plpgsql
VOLATILE
AS $$
BEGIN
    PERFORM tgsis.version_id(p_name);
    PERFORM set_config('tgsis.version', p_name, coalesce(p_local, false));
    PERFORM set_config('tgsis.revision', '', coalesce(p_local, false));
    RETURN p_name;
END
$$;

COMMENT ON FUNCTION tgsis.goto_version(text, boolean) IS
    'work in a version from now on (the viewing revision is cleared); p_local => true: only until the transaction ends (for poolers in transaction mode)';

-- ==== versioning/goto_revision.sql ====
-- tgsis.goto_revision(version, revision, local): look at an older revision of a version's history (read-only).
CREATE FUNCTION tgsis.goto_revision(p_version text, p_revision integer, p_local boolean DEFAULT false)
RETURNS integer
LANGUAGE plpgsql
VOLATILE
AS $$
BEGIN
    IF p_revision IS NULL THEN
        RAISE EXCEPTION 'goto_revision needs a revision' USING ERRCODE = 'TG100';
    END IF;
    PERFORM tgsis.revision_set(tgsis.version_id(p_version), p_revision);  -- TG200 unless in its history
    PERFORM set_config('tgsis.version', p_version, coalesce(p_local, false));
    PERFORM set_config('tgsis.revision', p_revision::text, coalesce(p_local, false));
    RETURN p_revision;
END
$$;

COMMENT ON FUNCTION tgsis.goto_revision(text, integer, boolean) IS
    'look at revision r of a version''s history (read-only until goto_version): its working set, or its own older revisions';

-- ==== versioning/plain_write_check.sql ====
-- tgsis.plain_write_check(schema, table): refuse (TG305) a write to a table that is not versioned while the session is not in DEFAULT's working revision.
-- A plain table holds one state, the one every version reads: a write made
-- "in" version v1 (goto_version, SET tgsis.version) would silently land in
-- DEFAULT. The write functions of features (new_geometry, delete_geometry,
-- refresh_geometry, add_instant, delete_instant) call this first; the views of
-- versioned tables need no such check. Reads only settings and the registry.
CREATE FUNCTION tgsis.plain_write_check(p_schema text, p_table text)
RETURNS void
LANGUAGE plpgsql
STABLE
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_version text := tgsis.get_working_version();
    v_viewing integer := tgsis.get_viewing_revision();
    v_working integer;
BEGIN
    IF EXISTS (SELECT FROM tgsis.versioned_tables t WHERE t.schemaname = p_schema AND t.tablename = p_table) THEN
        RETURN;
    END IF;
    SELECT v.workingrevision INTO v_working FROM tgsis.versions v WHERE v.name = v_version;
    IF v_version = 'DEFAULT' AND (v_viewing IS NULL OR v_viewing = v_working) THEN
        RETURN;
    END IF;
    IF v_version <> 'DEFAULT' THEN
        RAISE EXCEPTION 'table %.% is not versioned: a write in version % would change DEFAULT, which every version reads',
                        p_schema, p_table, quote_literal(v_version)
            USING ERRCODE = 'TG305',
                  DETAIL = format('The session works in version %L (setting tgsis.version), but feature versioning is off, '
                                  'so the table holds one state for all versions. Nothing was written.', v_version),
                  HINT = 'SELECT tgsis.enable_feature_versioning() to write features in versions, '
                         'or SELECT tgsis.goto_version(''DEFAULT'') to write in DEFAULT';
    END IF;
    RAISE EXCEPTION 'table %.% is not versioned: DEFAULT viewed at revision % cannot be written', p_schema, p_table, v_viewing
        USING ERRCODE = 'TG305',
              DETAIL = 'The session looks at an older revision (setting tgsis.revision); the table holds only the current state. Nothing was written.',
              HINT = 'SELECT tgsis.goto_version(''DEFAULT'') to write the current state';
END
$$;

COMMENT ON FUNCTION tgsis.plain_write_check(text, text) IS
    'refuse (TG305) a write to a table that is not versioned while the session works in a version other than DEFAULT or views an older revision: the write would land in DEFAULT; no-op for versioned tables';

-- ==== versioning/check_writable_revision.sql ====
-- tgsis.check_writable_revision(version, working revision): TG301 while the session views a revision other than the working one.
-- Shared by the write paths (tgsis.write_revision) and save_revision, which
-- must refuse before they lock or write anything.
CREATE FUNCTION tgsis.check_writable_revision(p_version text, p_working integer)
RETURNS void
LANGUAGE plpgsql
STABLE
AS $$
DECLARE
    v_viewing integer := tgsis.get_viewing_revision();  -- TG100 for a malformed setting
    v_saved   text;
BEGIN
    IF v_viewing IS NULL OR v_viewing = p_working THEN
        RETURN;
    END IF;
    SELECT r.name INTO v_saved FROM tgsis.revisions r WHERE r.revision = v_viewing;
    RAISE EXCEPTION 'version % is viewed at revision %, which cannot be changed', quote_literal(p_version), v_viewing
        USING ERRCODE = 'TG301',
              DETAIL = CASE WHEN v_saved IS NOT NULL
                            THEN format('Revision %s was saved as %L and is frozen; only the working revision %s of %s can change.',
                                        v_viewing, v_saved, p_working, p_version)
                            ELSE format('Only the working revision %s of %s can change.', p_working, p_version) END,
              HINT = format('SELECT tgsis.goto_version(%L) to work in its working revision', p_version);
END
$$;

COMMENT ON FUNCTION tgsis.check_writable_revision(text, integer) IS
    'raise TG301 (naming the viewed revision, and its name when saved) while the session views a revision of the version other than its working revision';

-- ==== versioning/write_revision.sql ====
-- tgsis.write_revision(): the version, revision and revision set a write of this session uses, or TG301/TG002 if it may not write.
-- Every write path calls it: the statement and row triggers of versioned
-- views, the statement triggers of storage, the client's bulk paths. It
-- share-locks the version's row until the transaction ends, so that
-- create_version, save_revision, merge and refresh (which lock it for update)
-- never hand the working revision on while a writer is still labelling rows
-- with it; the row is locked only when the calling role holds the write
-- right, so that nobody else can take that lock and keep it (a reader
-- holding it in an open transaction would stop them all).
-- The row triggers call it once per row rather than trusting the check of
-- their statement trigger: the session's version is a setting, which a
-- function called by the statement itself could change between rows. So
-- the usual case is one query: the right (tgsis_admin, the version's owner,
-- a grant, an ancestor's owner: tgsis.holds_version_privilege's rule, in
-- its cheapest order) is part of the locking query's condition.
CREATE FUNCTION tgsis.write_revision(OUT versionid integer, OUT revision integer, OUT revisions integer[])
LANGUAGE plpgsql
VOLATILE
SECURITY DEFINER
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_name    text := coalesce(nullif(current_setting('tgsis.version', true), ''), 'DEFAULT');
    v_viewing text := nullif(btrim(current_setting('tgsis.revision', true)), '');
    v_role    name := tgsis.calling_role();
BEGIN
    SELECT v.versionid, v.workingrevision, v.workingset INTO versionid, revision, revisions
      FROM tgsis.versions v
     WHERE v.name = v_name
       AND (pg_has_role(v_role, 'tgsis_admin', 'USAGE')
            OR v.owner = v_role
            OR EXISTS (SELECT FROM tgsis.version_privileges p LEFT JOIN pg_roles r ON r.rolname = p.grantee
                        WHERE p.versionid = v.versionid AND p.privilege = 'write'
                          AND (p.grantee = 'public' OR (r.oid IS NOT NULL AND pg_has_role(v_role, r.oid, 'USAGE'))))
            OR tgsis.is_version_owner(v.versionid, v_role))
       FOR SHARE OF v;
    IF NOT FOUND THEN
        -- no such version, or no right (require_version_privilege says which right, whose, and the grant)
        PERFORM tgsis.require_version_privilege(tgsis.version_id(v_name), 'write', 'write in');
        -- it had the right after all: deleted, or given the right, by a transaction this one waited for
        RAISE EXCEPTION 'version % changed while this write waited for it', quote_literal(v_name)
            USING ERRCODE = 'serialization_failure', HINT = 'retry the transaction';
    END IF;
    IF v_viewing IS NOT NULL THEN
        PERFORM tgsis.check_writable_revision(v_name, revision);  -- TG301 (the error ends the lock with the transaction)
    END IF;
END
$$;

COMMENT ON FUNCTION tgsis.write_revision() IS
    'version id, working revision and working set for a write in the session''s version, share-locking the version until commit when the calling role holds the write right; TG002 without it, TG301 while an older revision is viewed (the error ends the lock with the transaction)';

-- ==== versioning/storage_write_check.sql ====
-- tgsis.storage_write_check(): BEFORE statement trigger on every <table>_ver: direct writes need the write right on the session's version.
-- Reads and writes normally go through the view; the bulk path of the client
-- COPYs straight into storage (one trigger call per statement, not per row).
-- Only INSERT is granted on storage to roles other than its owner (updates
-- and deletes go through the views and tgsis's functions); the rows an
-- INSERT writes are checked after it by tgsis.storage_rows_check. The
-- trigger's WHEN spares the table's owner (as whom the views' row triggers
-- write) and tgsis's owner (whose functions merge, refresh and compress).
-- Invoker's rights, so that current_user is the writer; the search_path is
-- pinned so that no object of the writer's can stand in for pg_catalog's.
CREATE FUNCTION tgsis.storage_write_check()
RETURNS trigger
LANGUAGE plpgsql
VOLATILE
SET search_path = pg_catalog, pg_temp
AS $$
BEGIN
    PERFORM tgsis.write_revision();  -- TG002 without the write right, TG301 while viewing; share-locks the version
    RETURN NULL;
END
$$;

COMMENT ON FUNCTION tgsis.storage_write_check() IS
    'BEFORE statement trigger of <table>_ver storage: a role other than the table''s or tgsis''s owner writing storage directly needs the write right on its session''s version (and not to be viewing an old revision)';

-- ==== versioning/storage_rows_check.sql ====
-- tgsis.storage_rows_check(): AFTER INSERT statement trigger on every <table>_ver: rows written directly belong to the session's working revision.
-- A role writing storage directly (the client's COPY upload) may only add
-- live rows labelled with the working revision of a version where it holds
-- the write right, and only to objects no other version has locked. The rows
-- are read from the statement's transition table, once per statement (a
-- row trigger would double the upload); a wrong one fails the statement,
-- naming how many rows and which revision they had to carry.
-- Trigger arguments: object class, object key column.
CREATE FUNCTION tgsis.storage_rows_check()
RETURNS trigger
LANGUAGE plpgsql
VOLATILE
SECURITY DEFINER
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_write record;
    v_bad   bigint;
    v_first text;
    v_keys  text[];
BEGIN
    SELECT * INTO v_write FROM tgsis.write_revision();  -- TG002, TG301
    SELECT count(*), min(n.revision::text) INTO v_bad, v_first
      FROM tgsis_new_rows n
     WHERE n.revision IS DISTINCT FROM v_write.revision OR n.lastrevs IS DISTINCT FROM '{}'::integer[];
    IF v_bad > 0 THEN
        RAISE EXCEPTION '% row(s) written into %.% are not live rows of revision %, the working revision of version %',
                v_bad, TG_TABLE_SCHEMA, TG_TABLE_NAME, v_write.revision, quote_literal(tgsis.get_working_version())
            USING ERRCODE = 'TG002',
                  DETAIL = format('Rows written directly into storage must have revision = %s and lastrevs = ''{}'' (one had revision %s).',
                                  v_write.revision, coalesce(v_first, 'NULL')),
                  HINT = format('write through the view %I.%I, or label the rows with SELECT revision FROM tgsis.write_revision()',
                                TG_TABLE_SCHEMA, left(TG_TABLE_NAME, -4));
    END IF;
    IF EXISTS (SELECT FROM tgsis.object_locks l WHERE l.objectclass = TG_ARGV[0]) THEN
        PERFORM tgsis.check_key_type(TG_RELID, TG_ARGV[1]);
        EXECUTE format('SELECT array_agg(DISTINCT n.%I::text) FROM tgsis_new_rows n', TG_ARGV[1]) INTO v_keys;
        PERFORM tgsis.check_objects_unlocked(TG_ARGV[0], v_keys, v_write.versionid);
    END IF;
    RETURN NULL;
END
$$;

COMMENT ON FUNCTION tgsis.storage_rows_check() IS
    'AFTER INSERT statement trigger of <table>_ver storage (transition table tgsis_new_rows): rows a role other than the owners writes directly must be live rows of its working revision, in a version where it holds the write right, of objects no other version locked';

-- ==== versioning/view_write_check.sql ====
-- tgsis.view_write_check(): statement trigger on every versioned view: the write right on the session's version, once per statement.
-- SECURITY DEFINER so that roles writing the view need no right on schema
-- tgsis; the rights checked are the calling role's (tgsis.calling_role).
CREATE FUNCTION tgsis.view_write_check()
RETURNS trigger
LANGUAGE plpgsql
VOLATILE
SECURITY DEFINER
SET search_path = pg_catalog, pg_temp
AS $$
BEGIN
    PERFORM tgsis.write_revision();  -- TG002 without the write right, TG301 while viewing
    RETURN NULL;
END
$$;

COMMENT ON FUNCTION tgsis.view_write_check() IS
    'BEFORE statement trigger of versioned views: TG002 unless the calling role holds the write right on its session''s version (the row triggers then skip that check)';

-- ==== versioning/next_working_revision.sql ====
-- tgsis.next_working_revision(versionid, base, initrevision): freeze a version's working revision and hand it a new one.
-- The frozen revision keeps the set its version saw (revisions.visibleset),
-- which is what goto_revision shows later. With p_base the version is
-- re-based (merge, refresh): its new working set is p_base plus the new
-- revision and its initrevision p_initrevision. Returns the new revision.
-- The caller holds the version's row lock.
CREATE FUNCTION tgsis.next_working_revision(
    p_versionid    integer,
    p_base         integer[] DEFAULT NULL,
    p_initrevision integer   DEFAULT NULL)
RETURNS integer
LANGUAGE plpgsql
VOLATILE
AS $$
DECLARE
    v_version tgsis.versions;
    v_next    integer;
BEGIN
    SELECT * INTO v_version FROM tgsis.versions WHERE versionid = p_versionid;
    UPDATE tgsis.revisions SET visibleset = v_version.workingset WHERE revision = v_version.workingrevision;
    v_next := nextval('tgsis.revision_seq');
    INSERT INTO tgsis.revisions (revision, versionid, created_by) VALUES (v_next, p_versionid, tgsis.calling_role());
    UPDATE tgsis.versions
       SET workingrevision = v_next,
           workingset = coalesce(p_base, workingset) || v_next,
           initrevision = coalesce(p_initrevision, initrevision)
     WHERE versionid = p_versionid;
    RETURN v_next;
END
$$;

COMMENT ON FUNCTION tgsis.next_working_revision(integer, integer[], integer) IS
    'freeze a version''s working revision (storing the set it saw) and give it a new one, optionally re-based on p_base / p_initrevision; returns the new revision';

-- ==== versioning/create_version.sql ====
-- tgsis.create_version(name, parent): a new child version; returns its working revision.
-- Hand-out order (observable, part of the contract): the child's initrevision
-- is the parent's working revision; then the parent gets a new revision; then
-- the child gets its first one.
-- p_base bases the child on an older, frozen revision of the parent instead
-- (a conflicting check-in's child starts from the state the check-out saw,
-- so that its edit and the parent's later ones meet in find_conflicts): then
-- initrevision := p_base, the child sees what that revision saw, and the
-- parent, whose later changes are in later revisions already, gets no new
-- revision. Only the parent's own revisions since its base qualify (those
-- find_conflicts and merge compare with: an older one, from before a merge
-- or refresh re-based the parent, or a revision of an ancestor, would hide
-- changes from the conflict check); p_base = the working revision is the
-- default behaviour.
CREATE FUNCTION tgsis.create_version(p_name text, p_parent text DEFAULT 'DEFAULT', p_description text DEFAULT NULL,
                                     p_base integer DEFAULT NULL)
RETURNS integer
LANGUAGE plpgsql
VOLATILE
SECURITY DEFINER
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_parent     tgsis.versions;
    v_child_rev  integer;
    v_child_id   integer;
    v_constraint text;
    v_base       integer;
    v_baseset    integer[];
BEGIN
    PERFORM tgsis.check_version_name(p_name);
    PERFORM tgsis.require_version_privilege(tgsis.version_id(p_parent), 'create', 'create a child of');
    -- waits for writers of the parent's working revision (write_revision share-locks it)
    SELECT * INTO v_parent FROM tgsis.versions WHERE name = p_parent FOR UPDATE;
    IF NOT FOUND THEN
        -- deleted (or merged away) by the transaction this one waited for: without
        -- this check the new version would get a NULL parent and a NULL-violation
        RAISE EXCEPTION 'version % does not exist', quote_literal(p_parent)
            USING ERRCODE = 'TG200', DETAIL = 'It was deleted while this create_version waited for it.';
    END IF;
    IF EXISTS (SELECT FROM tgsis.versions WHERE name = p_name) THEN
        RAISE EXCEPTION 'version % exists already', quote_literal(p_name)
            USING ERRCODE = 'TG201', HINT = 'choose another name, or tgsis.delete_version it first';
    END IF;

    IF p_base IS NULL OR p_base = v_parent.workingrevision THEN
        v_base := v_parent.workingrevision;
        v_baseset := v_parent.workingset;
        PERFORM tgsis.next_working_revision(v_parent.versionid);
    ELSE
        -- the parent's row lock keeps a merge or refresh from re-basing it meanwhile. The base
        -- must see all the parent sees now but the parent's own later revisions: those are what
        -- find_conflicts and merge_version read as the parent's side (after a refresh the parent
        -- also sees ancestors' revisions the base did not, which no conflict check would show)
        SELECT r.revision, r.visibleset INTO v_base, v_baseset FROM tgsis.revisions r
         WHERE r.revision = p_base AND r.versionid = v_parent.versionid AND r.visibleset IS NOT NULL
           AND r.visibleset <@ v_parent.workingset
           AND NOT EXISTS (SELECT FROM unnest(v_parent.workingset) AS w(rev)
                            WHERE w.rev <> ALL (r.visibleset)
                              AND NOT (w.rev > p_base AND EXISTS (SELECT FROM tgsis.revisions o
                                                                   WHERE o.revision = w.rev
                                                                     AND o.versionid = v_parent.versionid)));
        IF NOT FOUND THEN
            RAISE EXCEPTION 'revision % is not a frozen revision of version % since its base', p_base, quote_literal(p_parent)
                USING ERRCODE = 'TG200',
                      DETAIL = format('A child can be based on the working revision of %s or on one of its own frozen '
                                      'revisions since it was last merged or refreshed; revision %s %s.', p_parent, p_base,
                                      CASE WHEN NOT EXISTS (SELECT FROM tgsis.revisions r WHERE r.revision = p_base)
                                           THEN 'does not exist (never handed out, or removed by compress_versions or delete_version)'
                                           WHEN EXISTS (SELECT FROM tgsis.revisions r WHERE r.revision = p_base AND r.versionid <> v_parent.versionid)
                                           THEN 'belongs to version ' || (SELECT v.name FROM tgsis.revisions r JOIN tgsis.versions v USING (versionid) WHERE r.revision = p_base)
                                           ELSE 'is from before a merge or refresh re-based it' END),
                      HINT = 'pass p_base => NULL to base the child on the parent''s working revision';
        END IF;
    END IF;

    v_child_rev := nextval('tgsis.revision_seq');
    BEGIN
        INSERT INTO tgsis.versions (name, parentid, initrevision, workingrevision, workingset, owner, description)
        VALUES (p_name, v_parent.versionid, v_base, v_child_rev, v_baseset || v_child_rev,
                tgsis.calling_role(), p_description)
        RETURNING versionid INTO v_child_id;
    EXCEPTION WHEN unique_violation THEN
        GET STACKED DIAGNOSTICS v_constraint = CONSTRAINT_NAME;
        IF v_constraint IS DISTINCT FROM 'versions_name_key' THEN
            RAISE;
        END IF;
        -- a concurrent create_version of the same name under another parent (it
        -- locked that parent, not ours, so the check above could not see it yet):
        -- the unique index waited for it; say so as the check above would have
        RAISE EXCEPTION 'version % exists already', quote_literal(p_name)
            USING ERRCODE = 'TG201', HINT = 'choose another name, or tgsis.delete_version it first',
                  DETAIL = 'It was created by a concurrent transaction.';
    END;
    INSERT INTO tgsis.revisions (revision, versionid, created_by) VALUES (v_child_rev, v_child_id, tgsis.calling_role());
    RETURN v_child_rev;
END
$$;

COMMENT ON FUNCTION tgsis.create_version(text, text, text, integer) IS
    'create a child version of p_parent (default DEFAULT): initrevision := parent''s working revision, then a new revision for the parent, then one for the child; with p_base (a frozen revision of the parent since its base) the child is based on that revision and the parent gets none; returns the child''s working revision';

-- ==== versioning/save_revision.sql ====
-- tgsis.save_revision(name): freeze the working revision of the session's version under a name; start a new one.
-- The checks come first and take no lock; then the version's row is locked
-- for update, which waits for open writers of the version (they share-lock
-- it) and for another save. Taking the writers' share lock first and then
-- upgrading it would deadlock two saves in one version (each holding the
-- share lock the other's upgrade waits for). The revision frozen is the
-- working revision once the lock is held: a save this one waited for has
-- handed on the one it would have seen before.
CREATE FUNCTION tgsis.save_revision(p_name text)
RETURNS integer
LANGUAGE plpgsql
VOLATILE
SECURITY DEFINER
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_version tgsis.versions;
    v_saved   integer;
BEGIN
    PERFORM tgsis.check_version_name(p_name, 'revision');
    SELECT * INTO v_version FROM tgsis.versions WHERE versionid = tgsis.version_id(tgsis.get_working_version());
    PERFORM tgsis.check_writable_revision(v_version.name, v_version.workingrevision);  -- TG301
    PERFORM tgsis.require_version_privilege(v_version.versionid, 'write', 'write in');  -- TG002
    SELECT * INTO v_version FROM tgsis.versions WHERE versionid = v_version.versionid FOR UPDATE;
    IF NOT FOUND THEN
        RAISE EXCEPTION 'version % does not exist', quote_literal(tgsis.get_working_version())
            USING ERRCODE = 'TG200', DETAIL = 'It was deleted while this save_revision waited for it.';
    END IF;
    v_saved := v_version.workingrevision;
    IF EXISTS (SELECT FROM tgsis.revisions WHERE versionid = v_version.versionid AND name = p_name) THEN
        RAISE EXCEPTION 'version % has a revision named % already', quote_literal(v_version.name), quote_literal(p_name)
            USING ERRCODE = 'TG201';
    END IF;
    UPDATE tgsis.revisions SET name = p_name, saved_at = now() WHERE revision = v_saved;
    PERFORM tgsis.next_working_revision(v_version.versionid);
    RETURN v_saved;
END
$$;

COMMENT ON FUNCTION tgsis.save_revision(text) IS
    'freeze the working revision of the session''s version under a name (it can be viewed, never changed) and give the version a new working revision; returns the frozen revision';

-- ==== versioning/version_tree.sql ====
-- The version tree for people: one row per version in depth-first order, with
-- its parent, depth, revisions and saved (named) revisions.
CREATE VIEW tgsis.version_tree AS
WITH RECURSIVE walk AS (
    SELECT v.versionid, v.name, NULL::text AS parent, 0 AS depth, ARRAY[v.name] AS path
      FROM tgsis.versions v WHERE v.parentid IS NULL
    UNION ALL
    SELECT c.versionid, c.name, w.name, w.depth + 1, w.path || c.name
      FROM tgsis.versions c JOIN walk w ON c.parentid = w.versionid
)
SELECT w.name, w.parent, w.depth, v.initrevision, v.workingrevision,
       (SELECT array_agg(r.revision ORDER BY r.revision) FROM tgsis.revisions r WHERE r.versionid = v.versionid) AS revisions,
       (SELECT coalesce(jsonb_object_agg(r.name, r.revision ORDER BY r.revision), '{}')
          FROM tgsis.revisions r WHERE r.versionid = v.versionid AND r.name IS NOT NULL) AS saved,
       v.owner, v.created_at, v.description, w.path
  FROM walk w JOIN tgsis.versions v ON v.versionid = w.versionid
 ORDER BY w.path;

COMMENT ON VIEW tgsis.version_tree IS 'versions in depth-first order with parent, depth, own revisions and saved revisions';
COMMENT ON COLUMN tgsis.version_tree.name IS 'version name';
COMMENT ON COLUMN tgsis.version_tree.parent IS 'parent version (NULL for DEFAULT)';
COMMENT ON COLUMN tgsis.version_tree.depth IS 'distance from DEFAULT';
COMMENT ON COLUMN tgsis.version_tree.initrevision IS 'parent''s working revision when the version was created';
COMMENT ON COLUMN tgsis.version_tree.workingrevision IS 'the revision its changes are labelled with';
COMMENT ON COLUMN tgsis.version_tree.revisions IS 'its own revisions, ascending';
COMMENT ON COLUMN tgsis.version_tree.saved IS 'saved revisions: {"name": revision}';
COMMENT ON COLUMN tgsis.version_tree.owner IS 'role that created it';
COMMENT ON COLUMN tgsis.version_tree.created_at IS 'when it was created';
COMMENT ON COLUMN tgsis.version_tree.description IS 'free text';
COMMENT ON COLUMN tgsis.version_tree.path IS 'names from DEFAULT down to it (the sort key)';

-- ==== versioning/set_version_validity.sql ====
-- tgsis.set_version_validity(version, valid_from, valid_to): the period [from, to) in which a version was believed true.
-- NULL valid_to: still believed; NULL valid_from: no period.
CREATE FUNCTION tgsis.set_version_validity(p_version text, p_valid_from timestamptz, p_valid_to timestamptz DEFAULT NULL)
RETURNS void
LANGUAGE plpgsql
VOLATILE
SECURITY DEFINER
SET search_path = pg_catalog, pg_temp
AS $$
BEGIN
    PERFORM tgsis.require_version_owner(tgsis.version_id(p_version), 'set the validity of');
    IF p_valid_to IS NOT NULL AND (p_valid_from IS NULL OR p_valid_to <= p_valid_from) THEN
        RAISE EXCEPTION 'validity period [%, %) of version % is empty', p_valid_from, p_valid_to, quote_literal(p_version)
            USING ERRCODE = 'TG100', HINT = 'valid_to must be later than valid_from (NULL: still believed)';
    END IF;
    UPDATE tgsis.versions SET valid_from = p_valid_from, valid_to = p_valid_to
     WHERE versionid = tgsis.version_id(p_version);
END
$$;

COMMENT ON FUNCTION tgsis.set_version_validity(text, timestamptz, timestamptz) IS
    'set the period [valid_from, valid_to) in which a version was believed true (valid_to NULL: still believed; valid_from NULL: none)';

-- ==== versioning/version_chain.sql ====
-- tgsis.version_chain(root): the versions with a validity period at or below root, in time order; TG100 unless they form a chain.
-- A chain: each is a descendant of the one before, and the periods do not
-- overlap (a mine that revises its model after every survey keeps one).
CREATE FUNCTION tgsis.version_chain(p_root text DEFAULT 'DEFAULT')
RETURNS TABLE (name text, valid_from timestamptz, valid_to timestamptz, depth integer)
LANGUAGE plpgsql
STABLE
AS $$
DECLARE
    v_prev record;
    v_row  record;
BEGIN
    FOR v_row IN
        WITH RECURSIVE below AS (
            SELECT v.versionid, v.name, 0 AS depth, ARRAY[v.versionid] AS path
              FROM tgsis.versions v WHERE v.versionid = tgsis.version_id(p_root)
            UNION ALL
            SELECT c.versionid, c.name, b.depth + 1, b.path || c.versionid
              FROM tgsis.versions c JOIN below b ON c.parentid = b.versionid)
        SELECT b.name, v.valid_from, v.valid_to, b.depth, b.path, v.versionid
          FROM below b JOIN tgsis.versions v USING (versionid)
         WHERE v.valid_from IS NOT NULL
         ORDER BY v.valid_from
    LOOP
        IF v_prev IS NOT NULL THEN
            IF NOT v_prev.versionid = ANY (v_row.path) THEN
                RAISE EXCEPTION 'versions % and % with validity periods are not on one line of descent', v_prev.name, v_row.name
                    USING ERRCODE = 'TG100', HINT = 'a chain of beliefs is a version, its child, its grandchild, ...';
            END IF;
            IF v_prev.valid_to IS NULL OR v_prev.valid_to > v_row.valid_from THEN
                RAISE EXCEPTION 'validity periods of versions % and % overlap', v_prev.name, v_row.name
                    USING ERRCODE = 'TG100', HINT = 'end the earlier one (tgsis.set_version_validity) where the later one starts';
            END IF;
        END IF;
        name := v_row.name; valid_from := v_row.valid_from; valid_to := v_row.valid_to; depth := v_row.depth;
        RETURN NEXT;
        v_prev := v_row;
    END LOOP;
END
$$;

COMMENT ON FUNCTION tgsis.version_chain(text) IS
    'versions with a validity period at or below p_root, oldest first; raises TG100 unless they form one line of descent with periods that do not overlap';

-- ==== versioning/version_believed_at.sql ====
-- tgsis.version_believed_at(at, root): the version of the chain below root believed true at a moment (NULL: none).
CREATE FUNCTION tgsis.version_believed_at(p_at timestamptz, p_root text DEFAULT 'DEFAULT')
RETURNS text
LANGUAGE sql
STABLE
AS $$
    SELECT c.name FROM tgsis.version_chain(p_root) AS c
     WHERE c.valid_from <= p_at AND (c.valid_to IS NULL OR p_at < c.valid_to)
$$;

COMMENT ON FUNCTION tgsis.version_believed_at(timestamptz, text) IS
    'name of the version believed true at p_at in the chain of versions with validity periods below p_root (tgsis.version_chain); NULL when none';

-- ==== versioning/resolve_table.sql ====
-- tgsis.resolve_table(name): the relation a name ('t' or 'schema.t') means in the caller's search_path, or TG200.
CREATE FUNCTION tgsis.resolve_table(p_table text)
RETURNS regclass
LANGUAGE plpgsql
STABLE
AS $$
DECLARE
    v_rel regclass;
BEGIN
    BEGIN
        v_rel := to_regclass(p_table);
    EXCEPTION WHEN invalid_name OR syntax_error OR feature_not_supported THEN  -- malformed names; db.schema.name
        v_rel := NULL;
    END;
    IF v_rel IS NULL THEN
        RAISE EXCEPTION 'table % does not exist', coalesce(quote_literal(p_table), 'NULL')
            USING ERRCODE = 'TG200', HINT = 'give it as name or schema.name, as it would be written in SQL';
    END IF;
    RETURN v_rel;
END
$$;

COMMENT ON FUNCTION tgsis.resolve_table(text) IS
    'the relation a table name (''t'' or ''schema.t'', quoted where SQL needs it) means in the caller''s search_path; raises TG200 if none';

-- ==== versioning/versioned_table.sql ====
-- tgsis.versioned_table(view): the catalog row of a versioned table (its view), or TG200.
CREATE FUNCTION tgsis.versioned_table(p_table regclass)
RETURNS tgsis.versioned_tables
LANGUAGE plpgsql
STABLE
AS $$
DECLARE
    v_row tgsis.versioned_tables;
BEGIN
    SELECT t.* INTO v_row
      FROM tgsis.versioned_tables t
      JOIN pg_catalog.pg_class c ON c.relname = t.tablename
      JOIN pg_catalog.pg_namespace n ON n.oid = c.relnamespace AND n.nspname = t.schemaname
     WHERE c.oid = p_table;
    IF NOT FOUND THEN
        RAISE EXCEPTION 'table % is not versioned', coalesce(p_table::text, 'NULL')
            USING ERRCODE = 'TG200', HINT = 'SELECT * FROM tgsis.versioned_tables lists the versioned tables';
    END IF;
    RETURN v_row;
END
$$;

COMMENT ON FUNCTION tgsis.versioned_table(regclass) IS
    'catalog row (tgsis.versioned_tables) of a versioned table, given as its view; raises TG200 if it is not versioned';

-- ==== versioning/check_key_type.sql ====
-- tgsis.check_key_type(storage, column): refuse (TG100) an object key column whose type is not built into PostgreSQL.
-- tgsis's definer code casts object keys to and from text as tgsis's owner
-- (validating keys, reading keys of rows written directly). enable_versioning
-- refuses such keys, but a table's owner can change the column's type
-- afterwards; a domain's check or a cast of a type of its own would then be
-- the owner's code run as tgsis's owner. So the definer code checks the type
-- again each time, before it casts.
CREATE FUNCTION tgsis.check_key_type(p_storage regclass, p_column text)
RETURNS void
LANGUAGE plpgsql
STABLE
AS $$
DECLARE
    v_type oid := (SELECT a.atttypid FROM pg_catalog.pg_attribute a
                    WHERE a.attrelid = p_storage AND a.attname = p_column AND NOT a.attisdropped);
BEGIN
    IF v_type IS NULL OR v_type >= 16384 THEN
        RAISE EXCEPTION 'the object key column % of % is %', quote_ident(p_column), p_storage,
                CASE WHEN v_type IS NULL THEN 'missing' ELSE format('of type %s, which is not built into PostgreSQL',
                                                                   pg_catalog.format_type(v_type, NULL)) END
            USING ERRCODE = 'TG100',
                  DETAIL = 'tgsis reads and compares object keys as its owner; a type of one''s own could run its owner''s code there.',
                  HINT = 'key the objects by a column of a built-in type (integer, bigint, text, uuid, ...)';
    END IF;
END
$$;

COMMENT ON FUNCTION tgsis.check_key_type(regclass, text) IS
    'raise TG100 unless the object key column of a versioned table''s storage is of a built-in type (checked before definer code casts keys)';

-- ==== versioning/storage_execute.sql ====
-- tgsis.storage_execute(dml, sql, $1..$5): run one statement tgsis built over a versioned table's storage, with the caller's rights.
-- The body every storage statement of tgsis runs through: directly when the
-- caller may run it as itself, and inside each table's runner
-- (<table>_ver_run(), SECURITY DEFINER, owned by the table's owner) when
-- tgsis's definer code acts on a table another role owns (tgsis.storage_run).
-- A statement (p_dml) gives one row: its row count; a query gives its rows,
-- each one text[]. The parameters are $1 text[], $2 integer[], $3 integer[],
-- $4 integer, $5 bigint[]. It runs with the rights of whoever calls it, so
-- PUBLIC may call it: it is SQL the caller could run itself.
CREATE FUNCTION tgsis.storage_execute(
    p_dml boolean,
    p_sql text,
    p_1   text[],
    p_2   integer[],
    p_3   integer[],
    p_4   integer,
    p_5   bigint[])
RETURNS SETOF text[]
LANGUAGE plpgsql
VOLATILE
AS $$
DECLARE
    v_count bigint;
BEGIN
    IF p_dml THEN
        EXECUTE p_sql USING p_1, p_2, p_3, p_4, p_5;
        GET DIAGNOSTICS v_count = ROW_COUNT;
        RETURN NEXT ARRAY[v_count::text];
    ELSE
        RETURN QUERY EXECUTE p_sql USING p_1, p_2, p_3, p_4, p_5;
    END IF;
END
$$;

COMMENT ON FUNCTION tgsis.storage_execute(boolean, text, text[], integer[], integer[], integer, bigint[]) IS
    'run one statement (p_dml: its row count as one row) or query (its text[] rows) over versioned storage with the caller''s rights; $1..$5 = p_1..p_5; the body of every <table>_ver_run()';

-- ==== versioning/storage_runner_source.sql ====
-- tgsis.storage_runner_source(schema, table): CREATE FUNCTION of a versioned table's runner <table>_ver_run().
-- tgsis's definer functions (merge, refresh, delete_version, compress,
-- conflicts, set-based deletes) run as tgsis's owner. What a statement on a
-- table runs besides the statement itself (its triggers and rules, the
-- expressions of its defaults, checks and indexes, casts of its row type)
-- is its owner's code: run as tgsis's owner, an application's table could
-- make any role its owner chose a superuser. So on a table another role
-- owns, they run their statements through this function, SECURITY DEFINER
-- and owned by the table's owner (enable_versioning sets it so): the
-- table's code then runs as the table's owner, who could run it anyway.
-- Besides its owner (and superusers) only tgsis_nobody may call it, as
-- which tgsis.storage_hop calls it, and it refuses to run unless tgsis is
-- calling it right now (tgsis.check_storage_call).
CREATE FUNCTION tgsis.storage_runner_source(p_schema text, p_table text)
RETURNS text
LANGUAGE sql
IMMUTABLE
PARALLEL SAFE
AS $$
    SELECT format(
        'CREATE FUNCTION %I.%I(p_dml boolean, p_sql text, p_1 text[], p_2 integer[], p_3 integer[], p_4 integer, p_5 bigint[]) '
        'RETURNS SETOF text[] LANGUAGE sql VOLATILE SECURITY DEFINER SET search_path = pg_catalog, pg_temp '
        'AS %L',
        p_schema, p_table || '_ver_run',
        format('SELECT tgsis.check_storage_call(%L); '
               'SELECT * FROM tgsis.storage_execute(p_dml, p_sql, p_1, p_2, p_3, p_4, p_5)',
               format('%I.%I', p_schema, p_table || '_ver_run')))
$$;

COMMENT ON FUNCTION tgsis.storage_runner_source(text, text) IS
    'CREATE FUNCTION statement of <schema>.<table>_ver_run(dml, sql, $1..$5), the SECURITY DEFINER runner through which tgsis''s definer code acts on storage another role owns (as that owner)';

-- ==== versioning/storage_calls.sql ====
-- tgsis.storage_calls: which runner tgsis's definer code is calling now, per backend.
-- A table's runner (<table>_ver_run()) may be called by tgsis_nobody, as
-- which tgsis.storage_hop runs. Code running as tgsis_nobody could then call
-- the runner of any table, e.g. a runner its owner made SECURITY INVOKER,
-- calling another owner's runner. So each runner first asks
-- tgsis.check_storage_call whether tgsis itself is calling it right now in
-- this backend: tgsis.storage_run records the call here (only tgsis's owner
-- may write this table) and removes it when the runner returns. Rows live
-- only as long as one call; UNLOGGED, nothing to keep across a crash.
CREATE UNLOGGED TABLE tgsis.storage_calls (
    backend integer PRIMARY KEY,
    runner  text    NOT NULL
);

COMMENT ON TABLE tgsis.storage_calls IS
    'the runner <schema>.<table>_ver_run() tgsis is calling now in each backend (tgsis.storage_run); runners refuse any other caller (tgsis.check_storage_call)';
COMMENT ON COLUMN tgsis.storage_calls.backend IS 'pg_backend_pid() of the session';
COMMENT ON COLUMN tgsis.storage_calls.runner IS 'the runner called, as quoted schema.name';

-- ==== versioning/check_storage_call.sql ====
-- tgsis.check_storage_call(runner): a runner's first step: refuse unless tgsis is calling it now in this backend.
-- See tgsis.storage_calls. SECURITY DEFINER: the runner runs as its table's
-- owner, who may not read tgsis.storage_calls.
CREATE FUNCTION tgsis.check_storage_call(p_runner text)
RETURNS void
LANGUAGE plpgsql
STABLE
SECURITY DEFINER
SET search_path = pg_catalog, pg_temp
AS $$
BEGIN
    IF NOT EXISTS (SELECT FROM tgsis.storage_calls c WHERE c.backend = pg_backend_pid() AND c.runner = p_runner) THEN
        RAISE EXCEPTION 'only tgsis may call %()', p_runner
            USING ERRCODE = 'TG002',
                  DETAIL = 'A versioned table''s runner acts on its storage for tgsis''s own functions (merges, deletes of versions).';
    END IF;
END
$$;

COMMENT ON FUNCTION tgsis.check_storage_call(text) IS
    'raise TG002 unless tgsis.storage_run is calling the runner p_runner (quoted schema.name) right now in this backend; the first statement of every <table>_ver_run()';

-- ==== versioning/storage_hop.sql ====
-- tgsis.storage_hop(schema, runner, dml, sql, $1..$5): call a table's runner as tgsis_nobody.
-- SECURITY DEFINER, owned by tgsis_nobody (see sql/core/nobody_role.sql):
-- a runner is SECURITY DEFINER, so it runs as its table's owner whoever
-- calls it; should its owner have made it SECURITY INVOKER, it runs as
-- tgsis_nobody, which may do nothing, rather than as tgsis's owner. Only
-- tgsis's owner calls it (tgsis.storage_run).
CREATE FUNCTION tgsis.storage_hop(
    p_schema text,
    p_runner text,
    p_dml    boolean,
    p_sql    text,
    p_1      text[],
    p_2      integer[],
    p_3      integer[],
    p_4      integer,
    p_5      bigint[])
RETURNS SETOF text[]
LANGUAGE plpgsql
VOLATILE
SECURITY DEFINER
SET search_path = pg_catalog, pg_temp
AS $$
BEGIN
    RETURN QUERY EXECUTE format('SELECT * FROM %I.%I($1, $2, $3, $4, $5, $6, $7)', p_schema, p_runner)
        USING p_dml, p_sql, p_1, p_2, p_3, p_4, p_5;
END
$$;

COMMENT ON FUNCTION tgsis.storage_hop(text, text, boolean, text, text[], integer[], integer[], integer, bigint[]) IS
    'call the runner p_schema.p_runner() of a versioned table as tgsis_nobody (no rights), so that a runner made SECURITY INVOKER cannot run as tgsis''s owner; for tgsis.storage_run only';

REVOKE ALL ON FUNCTION tgsis.storage_hop(text, text, boolean, text, text[], integer[], integer[], integer, bigint[]) FROM PUBLIC;
GRANT EXECUTE ON FUNCTION tgsis.storage_hop(text, text, boolean, text, text[], integer[], integer[], integer, bigint[])
    TO CURRENT_USER;
DO $do$
BEGIN
    -- giving a function to a role needs membership in it (or being a superuser)
    IF NOT pg_catalog.pg_has_role(current_user, 'tgsis_nobody', 'MEMBER') THEN
        BEGIN
            GRANT tgsis_nobody TO CURRENT_USER;
        EXCEPTION WHEN insufficient_privilege THEN
            RAISE EXCEPTION 'tgsis needs its owner % to be a member of tgsis_nobody', current_user
                USING ERRCODE = 'TG002',
                      HINT = format('Ask a DBA to run once: GRANT tgsis_nobody TO %I;', current_user);
        END;
    END IF;
END
$do$;
-- (and the new owner's CREATE on the schema, which it needs no longer afterwards)
GRANT CREATE ON SCHEMA tgsis TO tgsis_nobody;
ALTER FUNCTION tgsis.storage_hop(text, text, boolean, text, text[], integer[], integer[], integer, bigint[]) OWNER TO tgsis_nobody;
REVOKE CREATE ON SCHEMA tgsis FROM tgsis_nobody;

-- ==== versioning/storage_run.sql ====
-- tgsis.storage_run(table, dml, sql, $1..$5): run a statement over a versioned table's storage, as that storage's owner when tgsis's owner runs it.
-- p_sql names the storage itself (schema.<table>_ver, quoted); see
-- tgsis.storage_execute for p_dml, the parameters and the rows returned.
-- - Called by another role (an invoker function a reader or editor runs):
--   the statement runs with that role's rights, like any query of its own.
-- - Called in tgsis's definer code, as tgsis's owner, on storage tgsis's
--   owner owns (the feature tables): run directly, with the storage locked
--   first, so that it cannot be dropped and replaced by something else of
--   that name (its schema's owner could) between the owner check and the
--   statement.
-- - As tgsis's owner on storage another role owns: through its runner
--   <table>_ver_run() (tgsis.storage_runner_source), called from
--   tgsis.storage_hop as tgsis_nobody, with the call recorded in
--   tgsis.storage_calls for the runner to check: whatever the statement
--   runs of the table's own code (triggers, rules, defaults, checks, index
--   expressions, casts) runs as the table's owner, and a runner its owner
--   altered runs as tgsis_nobody at worst, never as tgsis's owner.
CREATE FUNCTION tgsis.storage_run(
    p_t   tgsis.versioned_tables,
    p_dml boolean,
    p_sql text,
    p_1   text[]    DEFAULT NULL,
    p_2   integer[] DEFAULT NULL,
    p_3   integer[] DEFAULT NULL,
    p_4   integer   DEFAULT NULL,
    p_5   bigint[]  DEFAULT NULL)
RETURNS SETOF text[]
LANGUAGE plpgsql
VOLATILE
AS $$
DECLARE
    v_storage text := format('%I.%I', p_t.schemaname, p_t.tablename || '_ver');
    v_tgsis   oid  := (SELECT n.nspowner FROM pg_catalog.pg_namespace n WHERE n.nspname = 'tgsis');
    v_owner   oid;
BEGIN
    IF current_user IS DISTINCT FROM pg_catalog.pg_get_userbyid(v_tgsis) THEN
        RETURN QUERY SELECT * FROM tgsis.storage_execute(p_dml, p_sql, p_1, p_2, p_3, p_4, p_5);
        RETURN;
    END IF;
    EXECUTE format('LOCK TABLE %s IN %s MODE', v_storage, CASE WHEN p_dml THEN 'ROW EXCLUSIVE' ELSE 'ACCESS SHARE' END);
    SELECT c.relowner INTO v_owner FROM pg_catalog.pg_class c WHERE c.oid = v_storage::regclass;
    IF v_owner = v_tgsis THEN
        RETURN QUERY SELECT * FROM tgsis.storage_execute(p_dml, p_sql, p_1, p_2, p_3, p_4, p_5);
        RETURN;
    END IF;
    IF pg_catalog.to_regprocedure(format('%I.%I(boolean, text, text[], integer[], integer[], integer, bigint[])',
                                         p_t.schemaname, p_t.tablename || '_ver_run')) IS NULL THEN
        RAISE EXCEPTION 'tgsis cannot act on %: its runner %.%() is missing', v_storage, quote_ident(p_t.schemaname),
                quote_ident(p_t.tablename || '_ver_run')
            USING ERRCODE = 'TG002',
                  DETAIL = 'tgsis acts on a table another role owns through that function, as the table''s owner.',
                  HINT = format('the table''s owner may run: SELECT tgsis.restore_storage_runner(%L)',
                                format('%I.%I', p_t.schemaname, p_t.tablename));
    END IF;
    INSERT INTO tgsis.storage_calls AS c (backend, runner)
    VALUES (pg_catalog.pg_backend_pid(), format('%I.%I', p_t.schemaname, p_t.tablename || '_ver_run'))
        ON CONFLICT (backend) DO UPDATE SET runner = excluded.runner;
    RETURN QUERY SELECT * FROM tgsis.storage_hop(p_t.schemaname, p_t.tablename || '_ver_run', p_dml, p_sql,
                                                 p_1, p_2, p_3, p_4, p_5);
    DELETE FROM tgsis.storage_calls c WHERE c.backend = pg_catalog.pg_backend_pid();
END
$$;

COMMENT ON FUNCTION tgsis.storage_run(tgsis.versioned_tables, boolean, text, text[], integer[], integer[], integer, bigint[]) IS
    'run a statement (p_dml: one row, its row count) or query (text[] rows) over a versioned table''s storage: with the caller''s rights, or, as tgsis''s owner on storage another role owns, through its runner <table>_ver_run() as that owner';

-- ==== versioning/create_storage_runner.sql ====
-- tgsis.create_storage_runner(schema, table): (re)create the runner <table>_ver_run() of a versioned table, owned by its storage's owner.
-- See tgsis.storage_runner_source for why it exists. Called by
-- enable_versioning, and by tgsis.restore_storage_runner when the runner
-- was dropped, altered or the storage changed owner. Runs with the
-- caller's rights: only a role that may act as the storage's owner can
-- give that owner a function.
CREATE FUNCTION tgsis.create_storage_runner(p_schema text, p_table text)
RETURNS void
LANGUAGE plpgsql
VOLATILE
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_owner name := (SELECT pg_get_userbyid(c.relowner) FROM pg_class c
                      WHERE c.oid = format('%I.%I', p_schema, p_table || '_ver')::regclass);
    v_sig   CONSTANT text := '(boolean, text, text[], integer[], integer[], integer, bigint[])';
BEGIN
    IF NOT pg_has_role(current_user, v_owner, 'USAGE') THEN
        RAISE EXCEPTION 'only the owner of %.% (%) may give it a runner', quote_ident(p_schema), quote_ident(p_table || '_ver'),
                v_owner
            USING ERRCODE = 'TG002';
    END IF;
    EXECUTE format('DROP FUNCTION IF EXISTS %I.%I%s', p_schema, p_table || '_ver_run', v_sig);
    EXECUTE tgsis.storage_runner_source(p_schema, p_table);
    EXECUTE format('ALTER FUNCTION %I.%I%s OWNER TO %I', p_schema, p_table || '_ver_run', v_sig, v_owner);
    EXECUTE format('REVOKE ALL ON FUNCTION %I.%I%s FROM PUBLIC', p_schema, p_table || '_ver_run', v_sig);
    EXECUTE format('GRANT EXECUTE ON FUNCTION %I.%I%s TO tgsis_nobody', p_schema, p_table || '_ver_run', v_sig);
    -- tgsis.storage_hop calls it by name, as tgsis_nobody
    IF NOT has_schema_privilege('tgsis_nobody', p_schema, 'USAGE') THEN
        BEGIN
            EXECUTE format('GRANT USAGE ON SCHEMA %I TO tgsis_nobody', p_schema);
        EXCEPTION WHEN insufficient_privilege THEN
            RAISE EXCEPTION 'tgsis_nobody needs USAGE on schema % to call the runner of %.%', quote_ident(p_schema),
                    quote_ident(p_schema), quote_ident(p_table)
                USING ERRCODE = 'TG002',
                      DETAIL = 'tgsis calls a versioned table''s runner as tgsis_nobody, a role with no rights.',
                      HINT = format('the owner of schema %I may run: GRANT USAGE ON SCHEMA %I TO tgsis_nobody', p_schema, p_schema);
        END;
    END IF;
    EXECUTE format('COMMENT ON FUNCTION %I.%I%s IS %L', p_schema, p_table || '_ver_run', v_sig,
                   format('tgsis versioning: runs tgsis''s statements on %I.%I as its owner (see tgsis.storage_runner_source); '
                          'only its owner may call it', p_schema, p_table || '_ver'));
END
$$;

COMMENT ON FUNCTION tgsis.create_storage_runner(text, text) IS
    '(re)create <schema>.<table>_ver_run(), the SECURITY DEFINER runner through which tgsis acts on a versioned table''s storage as its owner; the caller must be able to act as that owner';

-- ==== versioning/restore_storage_runner.sql ====
-- tgsis.restore_storage_runner(table): give a versioned table its runner back, for its owner.
CREATE FUNCTION tgsis.restore_storage_runner(p_table regclass)
RETURNS void
LANGUAGE plpgsql
VOLATILE
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_t tgsis.versioned_tables := tgsis.versioned_table(p_table);
BEGIN
    PERFORM tgsis.create_storage_runner(v_t.schemaname, v_t.tablename);
END
$$;

COMMENT ON FUNCTION tgsis.restore_storage_runner(regclass) IS
    'for the owner of a versioned table: re-create its runner <table>_ver_run() (after it was dropped or altered, or the storage changed owner), so that merges and deletes of versions act on it again';

-- ==== versioning/check_registrable.sql ====
-- tgsis.check_registrable(schema, table, owner): may tgsis record facts about this table for the calling role? Else TG002.
-- The definer functions that write tgsis.versioned_tables and
-- tgsis.versioning_dropped run as tgsis's owner, and other definer code later
-- acts on what those rows name. So a row may name only a table the calling
-- role owns (pg_has_role USAGE: it is, or acts as, a member of the owner), or
-- one tgsis itself created: owned by tgsis's owner (the owner of
-- tgsis.versioned_tables) and in schema tgsis or listed in tgsis.catalog,
-- which only tgsis's definer code writes. Another table of tgsis's owner (a
-- superuser's table, when tgsis's owner is that superuser) is not tgsis's.
CREATE FUNCTION tgsis.check_registrable(p_schema text, p_table text, p_owner oid)
RETURNS void
LANGUAGE plpgsql
STABLE
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_tgsis_owner oid := (SELECT relowner FROM pg_class WHERE oid = 'tgsis.versioned_tables'::regclass);
BEGIN
    IF p_owner IS NOT NULL AND pg_has_role(tgsis.calling_role(), p_owner, 'USAGE') THEN
        RETURN;
    END IF;
    IF p_owner = v_tgsis_owner
       AND (p_schema = 'tgsis'
            OR EXISTS (SELECT FROM tgsis.class_tables c WHERE c.schemaname = p_schema AND c.tablename = p_table)) THEN
        RETURN;
    END IF;
    RAISE EXCEPTION 'role % does not own %.%, and tgsis did not create it', tgsis.calling_role(), p_schema, p_table
        USING ERRCODE = 'TG002',
              DETAIL = format('Its owner is %s. tgsis records and later acts on tables their owners version, or its own.',
                              coalesce(pg_get_userbyid(p_owner)::text, 'unknown')),
              HINT = 'only the table''s owner may version it (or make it plain again)';
END
$$;

COMMENT ON FUNCTION tgsis.check_registrable(text, text, oid) IS
    'raise TG002 unless the calling role owns the table (through membership) or tgsis created it (owned by tgsis''s owner, in schema tgsis or listed in tgsis.catalog): what definer code may record in versioned_tables and versioning_dropped';

-- ==== versioning/record_dropped.sql ====
-- tgsis.record_dropped(table, object, is_index): record, before enable_versioning drops it, a constraint or unique index that cannot hold across versions.
-- tgsis.versioning_dropped is written only here (and by tgsis's own definer
-- code): restore_dropped_constraints EXECUTEs what it holds. So the caller
-- gives only the object's oid, and the definition is read from the system
-- catalogs (pg_get_constraintdef / pg_get_indexdef with a search_path of
-- pg_catalog alone, so qualified); the object must belong to, or refer to,
-- the table being versioned, a plain table the calling role owns (or one tgsis
-- created). A row recorded for an object that is then not dropped is
-- harmless: restore_dropped_constraints finds it present and forgets it.
CREATE FUNCTION tgsis.record_dropped(p_table regclass, p_object oid, p_is_index boolean DEFAULT false)
RETURNS integer
LANGUAGE plpgsql
VOLATILE
SECURITY DEFINER
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_schema text;
    v_name   text;
    v_kind   "char";
    v_owner  oid;
    v_id     integer;
BEGIN
    SELECT n.nspname, c.relname, c.relkind, c.relowner INTO v_schema, v_name, v_kind, v_owner
      FROM pg_class c JOIN pg_namespace n ON n.oid = c.relnamespace WHERE c.oid = p_table;
    IF v_kind IS DISTINCT FROM 'r'
       OR EXISTS (SELECT FROM tgsis.versioned_tables WHERE schemaname = v_schema AND tablename = v_name) THEN
        RAISE EXCEPTION 'constraints are recorded only for a plain table about to be versioned, not %',
                coalesce(p_table::text, 'NULL')
            USING ERRCODE = 'TG100', HINT = 'tgsis.enable_versioning records what it drops';
    END IF;
    PERFORM tgsis.check_registrable(v_schema, v_name, v_owner);

    IF coalesce(p_is_index, false) THEN
        INSERT INTO tgsis.versioning_dropped (schemaname, tablename, name, definition, is_index, dropped_for)
        SELECT v_schema, v_name, c.relname, pg_get_indexdef(i.indexrelid), true, format('%I.%I', v_schema, v_name)
          FROM pg_index i JOIN pg_class c ON c.oid = i.indexrelid
         WHERE i.indexrelid = p_object AND i.indrelid = p_table AND i.indisunique
           AND NOT EXISTS (SELECT FROM pg_constraint con WHERE con.conindid = i.indexrelid)
        RETURNING id INTO v_id;
    ELSE
        -- a constraint of another versioned table is recorded under its plain name
        INSERT INTO tgsis.versioning_dropped (schemaname, tablename, name, definition, refschema, reftable, dropped_for)
        SELECT n.nspname, coalesce(t.tablename, c.relname), con.conname, pg_get_constraintdef(con.oid), rn.nspname,
               rc.relname, format('%I.%I', v_schema, v_name)
          FROM pg_constraint con
          JOIN pg_class c ON c.oid = con.conrelid JOIN pg_namespace n ON n.oid = c.relnamespace
          LEFT JOIN tgsis.versioned_tables t ON t.schemaname = n.nspname AND t.tablename || '_ver' = c.relname
          LEFT JOIN pg_class rc ON rc.oid = con.confrelid LEFT JOIN pg_namespace rn ON rn.oid = rc.relnamespace
         WHERE con.oid = p_object AND con.contype IN ('u', 'x', 'f')
           AND (con.conrelid = p_table OR (con.contype = 'f' AND con.confrelid = p_table))
        RETURNING id INTO v_id;
    END IF;
    IF v_id IS NULL THEN
        RAISE EXCEPTION '% is not a % of %', p_object,
                CASE WHEN p_is_index THEN 'unique index (outside constraints)' ELSE 'unique, exclusion or foreign-key constraint' END,
                p_table
            USING ERRCODE = 'TG200';
    END IF;
    RETURN v_id;
END
$$;

REVOKE ALL ON FUNCTION tgsis.record_dropped(regclass, oid, boolean) FROM PUBLIC;

COMMENT ON FUNCTION tgsis.record_dropped(regclass, oid, boolean) IS
    'record in tgsis.versioning_dropped a constraint (or unique index) of, or referring to, a plain table the calling role owns, its definition read from the system catalogs, before enable_versioning drops it; returns the row id';

-- ==== versioning/register_versioned_table.sql ====
-- tgsis.register_versioned_table(view, ...): record in tgsis.versioned_tables a table enable_versioning has just versioned.
-- Definer functions (merges, deletes of versions, compress_versions,
-- disable_feature_versioning) act on what tgsis.versioned_tables names, as
-- tgsis's owner; only this function and tgsis's own definer code write it.
-- It records facts it checks in the system catalogs: <view> is a view with
-- tgsis's INSTEAD OF trigger calling <view>_ver_write(), over the table
-- <view>_ver of the same owner keyed by (key columns, revision); the calling
-- role owns them, or tgsis created them (tgsis.check_registrable). The object
-- class 'feature' is tgsis's own (model 1 and the feature classes).
CREATE FUNCTION tgsis.register_versioned_table(
    p_view           regclass,
    p_objectkeyfield text,
    p_objectclass    text,
    p_iudorder       integer,
    p_shortname      text,
    p_pkeyname       text,
    p_tablecomment   text,
    p_identity       text[])
RETURNS tgsis.versioned_tables
LANGUAGE plpgsql
VOLATILE
SECURITY DEFINER
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_expected text;
    v_schema text;
    v_table  text;
    v_kind   "char";
    v_owner  oid;
    v_ver    oid;
    v_keys   text[];
    v_tgsis  boolean;
    v_row    tgsis.versioned_tables;
BEGIN
    SELECT n.nspname, c.relname, c.relkind, c.relowner INTO v_schema, v_table, v_kind, v_owner
      FROM pg_class c JOIN pg_namespace n ON n.oid = c.relnamespace WHERE c.oid = p_view;
    SELECT c.oid INTO v_ver
      FROM pg_class c JOIN pg_namespace n ON n.oid = c.relnamespace
     WHERE n.nspname = v_schema AND c.relname = v_table || '_ver' AND c.relkind = 'r' AND c.relowner = v_owner;
    IF v_kind IS DISTINCT FROM 'v' OR v_ver IS NULL
       OR NOT EXISTS (SELECT FROM pg_trigger tr JOIN pg_proc p ON p.oid = tr.tgfoid
                       WHERE tr.tgrelid = p_view AND tr.tgname = 'tgsis_versioning'
                         AND p.pronamespace = to_regnamespace(quote_ident(v_schema)) AND p.proname = v_table || '_ver_write')
       OR (SELECT count(*) FROM pg_attribute WHERE attrelid = v_ver AND NOT attisdropped
              AND attname IN ('revision', 'lastrevs', 'revclosed')) <> 3 THEN
        RAISE EXCEPTION '% is not a table versioned by tgsis.enable_versioning', coalesce(p_view::text, 'NULL')
            USING ERRCODE = 'TG100', HINT = 'tgsis.enable_versioning versions a table and registers it';
    END IF;
    PERFORM tgsis.check_registrable(v_schema, v_table, v_owner);
    IF EXISTS (SELECT FROM tgsis.versioned_tables WHERE schemaname = v_schema AND tablename = v_table) THEN
        RAISE EXCEPTION 'table %.% is versioned already', v_schema, v_table USING ERRCODE = 'TG201';
    END IF;
    v_tgsis := v_owner = (SELECT relowner FROM pg_class WHERE oid = 'tgsis.versioned_tables'::regclass)
               AND (v_schema = 'tgsis' OR EXISTS (SELECT FROM tgsis.class_tables c
                                                   WHERE c.schemaname = v_schema AND c.tablename = v_table));
    -- tgsis's storage is versioned in the object class its registry row names (tgsis.model_tables),
    -- feature-class tables with the features; those classes are tgsis's alone
    v_expected := CASE WHEN NOT v_tgsis THEN NULL
                       WHEN v_schema = 'tgsis' THEN (SELECT t.objectclass FROM tgsis.model_tables t WHERE t.tablename = v_table)
                       ELSE 'feature' END;
    IF v_expected IS NULL AND (p_objectclass = 'feature' OR EXISTS (SELECT FROM tgsis.model_tables t
                                                                     WHERE t.objectclass = p_objectclass)) THEN
        RAISE EXCEPTION 'object class ''%'' holds tgsis''s stored objects and the feature classes, not %.%', p_objectclass,
                v_schema, v_table
            USING ERRCODE = 'TG100',
                  HINT = 'give the table an object class of its own (tgsis.enable_feature_versioning versions the features)';
    ELSIF v_expected IS NOT NULL AND p_objectclass <> v_expected THEN
        RAISE EXCEPTION '%.% is versioned with the features, in object class ''%''', v_schema, v_table, v_expected
            USING ERRCODE = 'TG100', HINT = 'tgsis.enable_feature_versioning versions it';
    END IF;
    -- the row key: the storage's primary key without revision
    SELECT array_agg(a.attname::text ORDER BY k.ord) FILTER (WHERE a.attname <> 'revision') INTO v_keys
      FROM pg_constraint con
      CROSS JOIN LATERAL unnest(con.conkey) WITH ORDINALITY AS k(attnum, ord)
      JOIN pg_attribute a ON a.attrelid = con.conrelid AND a.attnum = k.attnum
     WHERE con.conrelid = v_ver AND con.contype = 'p' AND con.conname = v_table || '_ver_pkey';
    IF v_keys IS NULL
       OR p_objectkeyfield IS NULL
       OR NOT EXISTS (SELECT FROM pg_attribute WHERE attrelid = p_view AND attname = p_objectkeyfield AND NOT attisdropped)
       OR p_pkeyname IS NULL OR octet_length(p_pkeyname) > 63
       OR EXISTS (SELECT FROM unnest(coalesce(p_identity, '{}')) AS u(col)
                   WHERE NOT EXISTS (SELECT FROM pg_attribute WHERE attrelid = v_ver AND attname = u.col AND attidentity = 'd')) THEN
        RAISE EXCEPTION 'the key, object key field or identity columns given for %.% are not those of its storage', v_schema, v_table
            USING ERRCODE = 'TG100', HINT = 'tgsis.enable_versioning versions a table and registers it';
    END IF;
    IF p_objectclass IS NULL OR btrim(p_objectclass) = '' OR p_iudorder IS NULL THEN
        RAISE EXCEPTION 'versioning %.% needs an object class and an iudorder', v_schema, v_table USING ERRCODE = 'TG100';
    END IF;
    IF EXISTS (SELECT FROM tgsis.versioned_tables WHERE objectclass = p_objectclass AND shortname = coalesce(p_shortname, v_table)) THEN
        RAISE EXCEPTION 'object class % has a table with short name % already', quote_literal(p_objectclass),
                quote_literal(coalesce(p_shortname, v_table))
            USING ERRCODE = 'TG201', HINT = 'pass another p_shortname';
    END IF;
    -- what tgsis.storage_run relies on when it acts on the storage as tgsis's owner
    PERFORM tgsis.check_key_type(v_ver::regclass, p_objectkeyfield);
    IF NOT EXISTS (SELECT FROM pg_proc
                    WHERE oid = to_regprocedure(format('%I.%I(boolean, text, text[], integer[], integer[], integer, bigint[])',
                                                       v_schema, v_table || '_ver_run'))
                      AND prosecdef AND proowner = v_owner) THEN
        RAISE EXCEPTION '%.% has no runner %.%() of its owner', v_schema, v_table, v_schema, v_table || '_ver_run'
            USING ERRCODE = 'TG100', HINT = 'tgsis.enable_versioning versions a table and registers it';
    END IF;

    INSERT INTO tgsis.versioned_tables (schemaname, tablename, shortname, objectkeyfield, objectclass, iudorder,
                                        keycolumns, pkeyname, tablecomment, identity_always, enabled_by)
    VALUES (v_schema, v_table, coalesce(p_shortname, v_table), p_objectkeyfield, p_objectclass, p_iudorder,
            v_keys, p_pkeyname, p_tablecomment, coalesce(p_identity, '{}'), tgsis.calling_role())
    RETURNING * INTO v_row;
    RETURN v_row;
END
$$;

REVOKE ALL ON FUNCTION tgsis.register_versioned_table(regclass, text, text, integer, text, text, text, text[]) FROM PUBLIC;

COMMENT ON FUNCTION tgsis.register_versioned_table(regclass, text, text, integer, text, text, text, text[]) IS
    'record in tgsis.versioned_tables a table tgsis.enable_versioning has just versioned, after checking in the system catalogs that it is (view, trigger, <table>_ver storage) and that the calling role owns it or tgsis created it; object class ''feature'' is tgsis''s own';

-- ==== versioning/unregister_versioned_table.sql ====
-- tgsis.unregister_versioned_table(schema, table): forget a versioned table that disable_versioning has just made plain.
-- Runs as tgsis's owner because only tgsis's definer code writes
-- tgsis.versioned_tables; it removes a row only when the system catalogs say
-- it is no longer true (<table> is a plain table again and <table>_ver is
-- gone), so a call can only remove stale rows.
CREATE FUNCTION tgsis.unregister_versioned_table(p_schema text, p_table text)
RETURNS boolean
LANGUAGE plpgsql
VOLATILE
SECURITY DEFINER
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_rel regclass := to_regclass(format('%I.%I', p_schema, p_table));
BEGIN
    IF v_rel IS NULL OR (SELECT relkind FROM pg_class WHERE oid = v_rel) <> 'r'
       OR to_regclass(format('%I.%I', p_schema, p_table || '_ver')) IS NOT NULL THEN
        RAISE EXCEPTION '%.% is still versioned (or gone): its registration stays', p_schema, p_table
            USING ERRCODE = 'TG202', HINT = 'tgsis.disable_versioning makes a versioned table plain and forgets it';
    END IF;
    DELETE FROM tgsis.versioned_tables WHERE schemaname = p_schema AND tablename = p_table;
    RETURN FOUND;
END
$$;

REVOKE ALL ON FUNCTION tgsis.unregister_versioned_table(text, text) FROM PUBLIC;

COMMENT ON FUNCTION tgsis.unregister_versioned_table(text, text) IS
    'remove the tgsis.versioned_tables row of a table that is plain again (checked in the system catalogs); returns whether there was one';

-- ==== versioning/forget_dropped.sql ====
-- tgsis.forget_dropped(id): remove a tgsis.versioning_dropped row once what it records exists again.
-- Runs as tgsis's owner because only tgsis's definer code writes
-- tgsis.versioning_dropped; it removes a row only when the constraint (on the
-- recorded table) or the index (in the recorded schema) is there, so a call
-- cannot make tgsis forget a constraint that is still to be restored.
CREATE FUNCTION tgsis.forget_dropped(p_id integer)
RETURNS boolean
LANGUAGE plpgsql
VOLATILE
SECURITY DEFINER
SET search_path = pg_catalog, pg_temp
AS $$
BEGIN
    DELETE FROM tgsis.versioning_dropped d
     WHERE d.id = p_id
       AND CASE WHEN d.is_index
                THEN EXISTS (SELECT FROM pg_class c JOIN pg_namespace n ON n.oid = c.relnamespace
                              WHERE n.nspname = d.schemaname AND c.relname = d.name AND c.relkind = 'i')
                ELSE EXISTS (SELECT FROM pg_constraint con JOIN pg_class c ON c.oid = con.conrelid
                               JOIN pg_namespace n ON n.oid = c.relnamespace
                              WHERE n.nspname = d.schemaname AND c.relname = d.tablename AND con.conname = d.name) END;
    RETURN FOUND;
END
$$;

REVOKE ALL ON FUNCTION tgsis.forget_dropped(integer) FROM PUBLIC;

COMMENT ON FUNCTION tgsis.forget_dropped(integer) IS
    'remove a tgsis.versioning_dropped row whose constraint or index exists again (checked in the system catalogs); returns whether it did';

-- ==== versioning/object_locks.sql ====
-- Object locks (as Workspace Manager's LockRows): a version takes an object
-- so that no other version (sibling, parent, child) can change it until the
-- lock is released; with exclusive, only the role that took it may change it
-- in that version. One lock per object across the whole tree. Locks go with
-- their version when it is deleted.
CREATE TABLE tgsis.object_locks (
    objectclass text        NOT NULL,
    objectkey   text        NOT NULL,
    versionid   integer     NOT NULL REFERENCES tgsis.versions (versionid) ON DELETE CASCADE,
    exclusive   boolean     NOT NULL DEFAULT false,
    locked_by   name        NOT NULL,
    locked_at   timestamptz NOT NULL DEFAULT now(),
    PRIMARY KEY (objectclass, objectkey)
);

CREATE INDEX object_locks_versionid_idx ON tgsis.object_locks (versionid);

COMMENT ON TABLE tgsis.object_locks IS
    'objects locked by a version: writes to them in any other version fail with TG303 (and, for exclusive locks, writes by other roles in that version)';
COMMENT ON COLUMN tgsis.object_locks.objectclass IS 'object class of the object (tgsis.versioned_tables.objectclass)';
COMMENT ON COLUMN tgsis.object_locks.objectkey IS 'object key, as text';
COMMENT ON COLUMN tgsis.object_locks.versionid IS 'the version holding the lock: the only one whose writes may change the object';
COMMENT ON COLUMN tgsis.object_locks.exclusive IS 'also keep other roles from changing the object in the holding version';
COMMENT ON COLUMN tgsis.object_locks.locked_by IS 'role that took the lock';
COMMENT ON COLUMN tgsis.object_locks.locked_at IS 'when the lock was taken';

-- ==== versioning/check_objects_unlocked.sql ====
-- tgsis.check_objects_unlocked(objectclass, keys, versionid, by_role): TG303 when another version (or role) holds a lock on one of the objects.
-- p_versionid is the version that writes (default: the session's working
-- version); with p_by_role an exclusive lock of that version also stops
-- other roles (a merge writes for the version, not for a role: it passes false).
CREATE FUNCTION tgsis.check_objects_unlocked(p_objectclass text, p_keys text[], p_versionid integer DEFAULT NULL,
                                             p_by_role boolean DEFAULT true)
RETURNS void
LANGUAGE plpgsql
STABLE
SECURITY DEFINER
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_writer integer := coalesce(p_versionid, tgsis.version_id(tgsis.get_working_version()));
    v_role   name := tgsis.calling_role();
    v_held   text;
    v_count  integer;
BEGIN
    SELECT string_agg(format('%s (locked by version %s, %s%s)', l.objectkey, v.name, quote_ident(l.locked_by),
                             CASE WHEN l.exclusive THEN ', exclusive' ELSE '' END), '; ' ORDER BY l.objectkey),
           count(*)
      INTO v_held, v_count
      FROM tgsis.object_locks l JOIN tgsis.versions v ON v.versionid = l.versionid
     WHERE l.objectclass = p_objectclass AND l.objectkey = ANY (p_keys)
       AND (l.versionid <> v_writer OR (p_by_role AND l.exclusive AND l.locked_by <> v_role));
    IF v_count > 0 THEN
        RAISE EXCEPTION '% of class % locked by another version or role: %',
                CASE WHEN v_count = 1 THEN 'object' ELSE v_count || ' objects' END, quote_literal(p_objectclass), v_held
            USING ERRCODE = 'TG303',
                  DETAIL = format('Writes from version %s cannot change them while the lock is held.',
                                  (SELECT name FROM tgsis.versions WHERE versionid = v_writer)),
                  HINT = 'the holder releases them with SELECT tgsis.unlock_objects(version, objectclass, keys); SELECT * FROM tgsis.object_locks lists locks';
    END IF;
END
$$;

COMMENT ON FUNCTION tgsis.check_objects_unlocked(text, text[], integer, boolean) IS
    'raise TG303 naming the objects (and holders) when objects of a class are locked by a version other than the writing one, or exclusively by another role';

-- ==== versioning/check_object_class.sql ====
-- tgsis.check_object_class(objectclass): TG200 unless some versioned table belongs to the object class.
CREATE FUNCTION tgsis.check_object_class(p_objectclass text)
RETURNS void
LANGUAGE plpgsql
STABLE
AS $$
BEGIN
    IF NOT EXISTS (SELECT FROM tgsis.versioned_tables WHERE objectclass = p_objectclass) THEN
        RAISE EXCEPTION 'object class % does not exist', coalesce(quote_literal(p_objectclass), 'NULL')
            USING ERRCODE = 'TG200', HINT = 'SELECT DISTINCT objectclass FROM tgsis.versioned_tables lists them';
    END IF;
END
$$;

COMMENT ON FUNCTION tgsis.check_object_class(text) IS 'raise TG200 naming the object class unless a versioned table belongs to it';

-- ==== versioning/visible_object_keys.sql ====
-- tgsis.visible_object_keys(objectclass, keys, revisions): which of the keys name an object a revision set sees in any table of its class.
CREATE FUNCTION tgsis.visible_object_keys(p_objectclass text, p_keys text[], p_revisions integer[])
RETURNS text[]
LANGUAGE plpgsql
VOLATILE
AS $$
DECLARE
    v_t     record;
    v_found text[] := '{}';
    v_some  text[];
    v_key   text;
    v_row   tgsis.versioned_tables;
BEGIN
    FOR v_t IN
        SELECT t AS tbl, t.schemaname, t.tablename, t.objectkeyfield, format_type(a.atttypid, a.atttypmod) AS keytype
          FROM tgsis.versioned_tables t
          JOIN pg_catalog.pg_attribute a
            ON a.attrelid = format('%I.%I', t.schemaname, t.tablename || '_ver')::regclass AND a.attname = t.objectkeyfield
         WHERE t.objectclass = p_objectclass
    LOOP
        v_row := v_t.tbl;
        PERFORM tgsis.check_key_type(format('%I.%I', v_t.schemaname, v_t.tablename || '_ver')::regclass, v_t.objectkeyfield);
        -- the keys cast to the column's type, so that the key index serves the lookup;
        -- a key that is no value of that type ('abc' for a bigint key) is a bad argument
        FOREACH v_key IN ARRAY coalesce(p_keys, '{}') LOOP
            BEGIN
                EXECUTE format('SELECT $1::%s', v_t.keytype) USING v_key;
            EXCEPTION WHEN data_exception THEN
                RAISE EXCEPTION 'object key % of class % is not a %', quote_nullable(v_key), quote_literal(p_objectclass), v_t.keytype
                    USING ERRCODE = 'TG100',
                          DETAIL = format('Column %I of %I.%I holds the keys of the class''s objects.',
                                          v_t.objectkeyfield, v_t.schemaname, v_t.tablename),
                          HINT = format('give keys that are %s values (for features: their ids)', v_t.keytype);
            END;
        END LOOP;
        -- read as the storage's owner from definer code (tgsis.storage_run)
        SELECT r INTO v_some FROM tgsis.storage_run(v_row, false, format(
            'SELECT coalesce(array_agg(DISTINCT v.%1$I::text), ''{}'') FROM %2$I.%3$I v
              WHERE v.%1$I = ANY ($1::%4$s[]) AND v.revision = ANY ($2) AND NOT (v.lastrevs && $2)',
            v_t.objectkeyfield, v_t.schemaname, v_t.tablename || '_ver', v_t.keytype), p_keys, p_revisions) AS r;
        v_found := v_found || v_some;
    END LOOP;
    RETURN ARRAY(SELECT DISTINCT k FROM unnest(v_found) AS k ORDER BY k);
END
$$;

COMMENT ON FUNCTION tgsis.visible_object_keys(text, text[], integer[]) IS
    'the keys among p_keys of objects of a class that the revision set sees in at least one of the class''s tables';

-- ==== versioning/lock_objects.sql ====
-- tgsis.lock_objects(version, objectclass, keys, exclusive): lock objects for a version so that no other version can change them; returns the locks taken.
-- Needs the write right on the version; the objects must exist in it.
-- Taking a lock the version holds already changes nothing (or makes it
-- exclusive for the caller); a lock held elsewhere fails with TG303.
CREATE FUNCTION tgsis.lock_objects(p_version text, p_objectclass text, p_keys text[], p_exclusive boolean DEFAULT false)
RETURNS integer
LANGUAGE plpgsql
VOLATILE
SECURITY DEFINER
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_id      integer := tgsis.version_id(p_version);
    v_role    name := tgsis.calling_role();
    v_missing text[];
    v_taken   integer;
BEGIN
    PERFORM tgsis.require_version_privilege(v_id, 'write', 'lock objects in');
    PERFORM tgsis.check_object_class(p_objectclass);
    IF p_keys IS NULL OR cardinality(p_keys) = 0 OR array_position(p_keys, NULL) IS NOT NULL THEN
        RAISE EXCEPTION 'no object keys to lock' USING ERRCODE = 'TG100', HINT = 'pass a non-empty array of keys without NULLs';
    END IF;
    SELECT array_agg(k ORDER BY k) INTO v_missing
      FROM unnest(p_keys) AS k
     WHERE k <> ALL (tgsis.visible_object_keys(p_objectclass, p_keys,
                                               (SELECT workingset FROM tgsis.versions WHERE versionid = v_id)));
    IF v_missing IS NOT NULL THEN
        RAISE EXCEPTION 'version % has no object % of class %', quote_literal(p_version), array_to_string(v_missing, ', '),
                quote_literal(p_objectclass)
            USING ERRCODE = 'TG200';
    END IF;

    INSERT INTO tgsis.object_locks (objectclass, objectkey, versionid, exclusive, locked_by)
    SELECT DISTINCT p_objectclass, k, v_id, coalesce(p_exclusive, false), v_role FROM unnest(p_keys) AS k
        ON CONFLICT DO NOTHING;
    GET DIAGNOSTICS v_taken = ROW_COUNT;
    -- locks the version held already: the caller may make its own exclusive
    UPDATE tgsis.object_locks SET exclusive = true, locked_by = v_role, locked_at = now()
     WHERE objectclass = p_objectclass AND objectkey = ANY (p_keys) AND versionid = v_id
       AND coalesce(p_exclusive, false) AND NOT exclusive;
    -- whatever is held elsewhere (or exclusively by another role) now fails the whole call
    PERFORM tgsis.check_objects_unlocked(p_objectclass, p_keys, v_id);
    RETURN v_taken;
END
$$;

COMMENT ON FUNCTION tgsis.lock_objects(text, text, text[], boolean) IS
    'lock objects of a class for a version (write right needed): other versions, and with p_exclusive other roles, cannot change them (TG303) until tgsis.unlock_objects; returns the number of new locks';

-- ==== versioning/unlock_objects.sql ====
-- tgsis.unlock_objects(version, objectclass, keys): release a version's locks (all of them, of a class, or of some keys); returns the locks released.
-- Needs the write right on the version; another role's exclusive lock only
-- its owner or a tgsis_admin may release.
CREATE FUNCTION tgsis.unlock_objects(p_version text, p_objectclass text DEFAULT NULL, p_keys text[] DEFAULT NULL)
RETURNS integer
LANGUAGE plpgsql
VOLATILE
SECURITY DEFINER
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_id       integer := tgsis.version_id(p_version);
    v_role     name := tgsis.calling_role();
    v_others   text;
    v_released integer;
BEGIN
    PERFORM tgsis.require_version_privilege(v_id, 'write', 'unlock objects in');
    IF p_objectclass IS NOT NULL THEN
        PERFORM tgsis.check_object_class(p_objectclass);
    END IF;
    IF NOT tgsis.is_version_owner(v_id, v_role) THEN
        SELECT string_agg(format('%s %s (%s)', objectclass, objectkey, quote_ident(locked_by)), ', ') INTO v_others
          FROM tgsis.object_locks
         WHERE versionid = v_id AND (p_objectclass IS NULL OR objectclass = p_objectclass)
           AND (p_keys IS NULL OR objectkey = ANY (p_keys)) AND exclusive AND locked_by <> v_role;
        IF v_others IS NOT NULL THEN
            RAISE EXCEPTION 'role % may not release exclusive locks of other roles: %', quote_ident(v_role), v_others
                USING ERRCODE = 'TG002', HINT = 'the version''s owner or a tgsis_admin may';
        END IF;
    END IF;
    DELETE FROM tgsis.object_locks
     WHERE versionid = v_id AND (p_objectclass IS NULL OR objectclass = p_objectclass)
       AND (p_keys IS NULL OR objectkey = ANY (p_keys));
    GET DIAGNOSTICS v_released = ROW_COUNT;
    RETURN v_released;
END
$$;

COMMENT ON FUNCTION tgsis.unlock_objects(text, text, text[]) IS
    'release object locks a version holds (all, those of a class, or of some keys); returns how many; another role''s exclusive lock needs the version''s owner or a tgsis_admin';

-- ==== versioning/rows_at.sql ====
-- tgsis.rows_at(NULL::table, version, revision): the rows of a versioned table as a version (at a revision) sees them.
-- Does not change the session's version. Usage:
--   SELECT * FROM tgsis.rows_at(NULL::public.wells, 'v1');
--   SELECT * FROM tgsis.rows_at(NULL::public.wells, 'DEFAULT', 12);
CREATE FUNCTION tgsis.rows_at(p_table anyelement, p_version text, p_revision integer DEFAULT NULL)
RETURNS SETOF anyelement
LANGUAGE plpgsql
STABLE
AS $$
DECLARE
    v_t    tgsis.versioned_tables;
    v_rel  oid := (SELECT typrelid FROM pg_catalog.pg_type WHERE oid = pg_typeof(p_table));
    v_set  integer[];
    v_cols text;
BEGIN
    IF v_rel = 0 THEN
        RAISE EXCEPTION 'rows_at takes a row of the versioned table, not a %', pg_typeof(p_table)
            USING ERRCODE = 'TG100', HINT = 'call it as tgsis.rows_at(NULL::schema.table, version[, revision])';
    END IF;
    v_t := tgsis.versioned_table(v_rel::regclass);  -- TG200 unless it is a versioned table's view
    v_set := tgsis.revision_set(tgsis.version_id(p_version), p_revision);
    SELECT string_agg(format('v.%I', attname), ', ' ORDER BY attnum) INTO v_cols
      FROM pg_catalog.pg_attribute WHERE attrelid = v_rel AND attnum > 0 AND NOT attisdropped;
    RETURN QUERY EXECUTE format('SELECT %s FROM %I.%I v WHERE (v.revision = ANY ($1)) IS TRUE '
                                'AND (NOT v.revclosed OR NOT (v.lastrevs && $1))',
                                v_cols, v_t.schemaname, v_t.tablename || '_ver')
                 USING v_set;
END
$$;

COMMENT ON FUNCTION tgsis.rows_at(anyelement, text, integer) IS
    'rows of a versioned table as version p_version sees them (at p_revision, default its working revision), without changing the session: tgsis.rows_at(NULL::schema.table, ''v1'')';

-- ==== versioning/versioned_view_source.sql ====
-- tgsis.versioned_view_source(schema, table, columns): the CREATE VIEW statement of a versioned table's view.
-- get_revisions() sits in scalar subqueries so that it runs once per query
-- (in the WHERE clause directly it would run once per row). Measured on
-- PostgreSQL 15 (bench/versioning.py), two choices of form:
--   * (revision = ANY (...)) IS TRUE keeps the revision test out of index
--     conditions: as an index condition on a non-leading column, btree runs
--     one index scan per revision in the set (4-6x the index work of a
--     one-object fetch); as a filter it costs a few ns per row;
--   * most rows are live (lastrevs empty): the stored flag revclosed spares
--     them the array overlap test, and reading the array at all (a short
--     array is copied out of the row to be read): 30-40 % of a full scan.
CREATE FUNCTION tgsis.versioned_view_source(p_schema text, p_table text, p_columns text[])
RETURNS text
LANGUAGE sql
IMMUTABLE
PARALLEL SAFE
AS $$
    SELECT format('CREATE VIEW %I.%I AS SELECT %s FROM %I.%I v '
                  'WHERE (v.revision = ANY ((SELECT tgsis.get_revisions(true))::integer[])) IS TRUE '
                  'AND (NOT v.revclosed OR NOT (v.lastrevs && (SELECT tgsis.get_revisions(true))))',
                  p_schema, p_table,
                  (SELECT string_agg(format('v.%I', c), ', ' ORDER BY o) FROM unnest(p_columns) WITH ORDINALITY AS u(c, o)),
                  p_schema, p_table || '_ver')
$$;

COMMENT ON FUNCTION tgsis.versioned_view_source(text, text, text[]) IS
    'source of the view <table> over <table>_ver that shows the rows of the session''s viewing revision set';

-- ==== versioning/versioning_trigger_source.sql ====
-- tgsis.versioning_trigger_source(schema, table, key columns, columns, pkey name, object class, object key column): the
-- CREATE FUNCTION statement of the INSTEAD OF trigger that routes writes on
-- the view <table> into <table>_ver. Generated per table with static SQL so
-- that PL/pgSQL caches the plans (dynamic SQL would be planned per row).
--
-- Concurrency. The view's row reached the trigger from the statement's
-- snapshot; the write is made on the row version that is current when it is
-- locked, as PostgreSQL's own re-check does for a plain table, or refused:
--   * update, delete: the visible row version of the key is locked (FOR
--     UPDATE waits for a concurrent writer and re-checks visibility after
--     it). If it is gone because that writer closed it (the first change of
--     a row inherited from an older revision writes a new row), the current
--     one is looked up again with a new snapshot. Its values must still be
--     the ones the statement read (binary equality, *=): otherwise the
--     statement computed its new values from a stale row, and the write
--     fails with 40001 (serialization_failure) naming table, key and version,
--     so that the client retries. A row deleted meanwhile is skipped, as on
--     a plain table.
--   * insert: a visible row of the key is share-locked, which waits for a
--     transaction closing it; the new row goes in with ON CONFLICT DO NOTHING
--     on the storage key, which waits for a concurrent insert of the same key
--     and revision. Either way a duplicate is the table's own 23505, never
--     one of the storage key.
--   * the object write lock (tgsis.object_lock_key) is held shared, so that
--     bulk writers of the object (check-in, save by difference, set-based
--     deletes, which take it exclusively) never decide from a state a view
--     write is changing.
-- Rights: tgsis.write_revision checks the calling role's write right on the
-- session's version for every row (the version is a setting that a function
-- called by the statement could change between rows) and share-locks it.
CREATE FUNCTION tgsis.versioning_trigger_source(
    p_schema    text,
    p_table     text,
    p_keys      text[],
    p_columns   text[],
    p_pkey      text,
    p_class     text,
    p_keyfield  text)
RETURNS text
LANGUAGE plpgsql
IMMUTABLE
AS $gen$
DECLARE
    v_ver      text := format('%I.%I', p_schema, p_table || '_ver');
    v_cols     text;
    v_new      text;
    v_assign   text;
    v_old_key  text;
    v_new_key  text;
    v_key_list text;
    v_visible  CONSTANT text := '(v.revision = ANY (v_set)) IS TRUE AND (NOT v.revclosed OR NOT (v.lastrevs && v_set))';
    v_current  text;
    v_same     text;
    v_dup      text;
    v_stale    text;
BEGIN
    SELECT string_agg(format('%I', c), ', ' ORDER BY o),
           string_agg(format('NEW.%I', c), ', ' ORDER BY o),
           string_agg(format('%I = NEW.%I', c, c), ', ' ORDER BY o),
           format('pg_catalog.record_image_eq(ROW(%s), ROW(%s))', string_agg(format('v_cur.%I', c), ', ' ORDER BY o),
                  string_agg(format('OLD.%I', c), ', ' ORDER BY o))
      INTO v_cols, v_new, v_assign, v_same
      FROM unnest(p_columns) WITH ORDINALITY AS u(c, o);
    SELECT string_agg(format('v.%I = OLD.%I', k, k), ' AND ' ORDER BY o),
           string_agg(format('v.%I = NEW.%I', k, k), ' AND ' ORDER BY o),
           string_agg(format('%I', k), ', ' ORDER BY o)
      INTO v_old_key, v_new_key, v_key_list
      FROM unnest(p_keys) WITH ORDINALITY AS u(k, o);
    -- the row version of the old key that is current now, locked: its place and revision, and its values
    v_current := format('SELECT v.ctid AS tgsis_ctid_, v.revision AS tgsis_revision_, %s INTO v_cur FROM %s v WHERE %s AND %s FOR UPDATE',
                        (SELECT string_agg(format('v.%I', c), ', ' ORDER BY o) FROM unnest(p_columns) WITH ORDINALITY AS u(c, o)),
                        v_ver, v_old_key, v_visible);
    -- the error a plain table would raise, so applications that catch 23505 keep working
    v_dup := format($dup$
            RAISE EXCEPTION 'duplicate key value violates unique constraint %%', %L
                USING ERRCODE = 'unique_violation',
                      DETAIL = format(%L, concat_ws(', ', %s), tgsis.get_working_version()),
                      CONSTRAINT = %L, TABLE = %L, SCHEMA = %L;$dup$,
        '"' || p_pkey || '"',
        'Key (' || replace(v_key_list, '%', '%%') || ')=(%s) already exists in version %s.',
        (SELECT string_agg(format('NEW.%I::text', k), ', ' ORDER BY o) FROM unnest(p_keys) WITH ORDINALITY AS u(k, o)),
        p_pkey, p_table, p_schema);
    -- what PostgreSQL raises when a repeatable-read transaction meets a concurrent update: clients retry it
    v_stale := format($stale$
            RAISE EXCEPTION 'could not serialize access due to concurrent update of row %%=(%%) of %%.%% in version %%',
                    %L, concat_ws(', ', %s), %L, %L, tgsis.get_working_version()
                USING ERRCODE = 'serialization_failure',
                      DETAIL = 'A transaction that committed after this statement read the row changed or replaced it; '
                               'writing values computed from the old row would undo that change.',
                      HINT = 'Retry the transaction.',
                      TABLE = %L, SCHEMA = %L;$stale$,
        '(' || v_key_list || ')',
        (SELECT string_agg(format('OLD.%I::text', k), ', ' ORDER BY o) FROM unnest(p_keys) WITH ORDINALITY AS u(k, o)),
        p_schema, p_table, p_table, p_schema);

    RETURN format($fn$
CREATE FUNCTION %1$I.%2$I()
RETURNS trigger
LANGUAGE plpgsql
SECURITY DEFINER
SET search_path = pg_catalog, pg_temp
AS $body$
-- Written by tgsis.enable_versioning: writes on the view %1$s.%3$s go to %4$s
-- as row versions labelled with the session's working revision (see
-- tgsis.versioning_trigger_source for how concurrent writers are handled).
DECLARE
    v_vid  integer;
    v_w    integer;
    v_set  integer[];
    v_keys text[];
    v_cur  record;
BEGIN
    -- the write right on the session's version (checked for every row), its working revision and set
    SELECT w.versionid, w.revision, w.revisions INTO v_vid, v_w, v_set FROM tgsis.write_revision() AS w;
    IF TG_OP = 'INSERT' THEN
        v_keys := ARRAY[NEW.%15$I::text];
    ELSIF TG_OP = 'DELETE' THEN
        v_keys := ARRAY[OLD.%15$I::text];
    ELSE
        v_keys := ARRAY[OLD.%15$I::text, NEW.%15$I::text];
    END IF;
    -- object locks: one index probe per row; the check names the holders
    IF EXISTS (SELECT FROM tgsis.object_locks l WHERE l.objectclass = %14$L AND l.objectkey = ANY (v_keys)) THEN
        PERFORM tgsis.check_objects_unlocked(%14$L, v_keys);
    END IF;
    -- no bulk writer of the object in flight (they take it exclusively)
    PERFORM pg_catalog.pg_advisory_xact_lock_shared(tgsis.object_lock_key(%14$L, v_keys[1], v_vid));
    IF cardinality(v_keys) = 2 AND v_keys[2] IS DISTINCT FROM v_keys[1] THEN
        PERFORM pg_catalog.pg_advisory_xact_lock_shared(tgsis.object_lock_key(%14$L, v_keys[2], v_vid));
    END IF;

    IF TG_OP = 'INSERT' THEN
        -- a visible row of the key: wait for a transaction closing it; if it stays, a duplicate
        PERFORM FROM %4$s v WHERE %6$s AND %9$s FOR SHARE;
        IF FOUND THEN%10$s
        END IF;
        -- waits for a concurrent insert of the same key in this revision
        INSERT INTO %4$s (%5$s, revision) VALUES (%7$s, v_w) ON CONFLICT ON CONSTRAINT %16$I DO NOTHING;
        IF NOT FOUND THEN%10$s
        END IF;
        RETURN NEW;
    END IF;

    %17$s;
    IF NOT FOUND THEN
        -- a transaction that committed since this statement read the row closed it: the row current now, if any
        %17$s;
        IF NOT FOUND THEN
            RETURN NULL;  -- deleted meanwhile: nothing to change, as on a plain table
        END IF;
    END IF;
    IF NOT (%18$s) THEN%19$s
    END IF;

    IF TG_OP = 'UPDATE' THEN
        IF ROW(%11$s) IS DISTINCT FROM ROW(%12$s) THEN
            -- a new key is a delete of the old key and an insert of the new one
            PERFORM FROM %4$s v WHERE %6$s AND %9$s FOR SHARE;
            IF FOUND THEN%10$s
            END IF;
            IF v_cur.tgsis_revision_ = v_w THEN
                DELETE FROM %4$s v WHERE v.ctid = v_cur.tgsis_ctid_;
            ELSE
                UPDATE %4$s v SET lastrevs = v.lastrevs || v_w WHERE v.ctid = v_cur.tgsis_ctid_;
            END IF;
            INSERT INTO %4$s (%5$s, revision) VALUES (%7$s, v_w) ON CONFLICT ON CONSTRAINT %16$I DO NOTHING;
            IF NOT FOUND THEN%10$s
            END IF;
        ELSIF v_cur.tgsis_revision_ = v_w THEN
            UPDATE %4$s v SET %8$s WHERE v.ctid = v_cur.tgsis_ctid_;
        ELSE
            UPDATE %4$s v SET lastrevs = v.lastrevs || v_w WHERE v.ctid = v_cur.tgsis_ctid_;
            INSERT INTO %4$s (%5$s, revision) VALUES (%7$s, v_w) ON CONFLICT ON CONSTRAINT %16$I DO NOTHING;
            IF NOT FOUND THEN%19$s
            END IF;
        END IF;
        RETURN NEW;
    END IF;
    IF v_cur.tgsis_revision_ = v_w THEN
        DELETE FROM %4$s v WHERE v.ctid = v_cur.tgsis_ctid_;
    ELSE
        UPDATE %4$s v SET lastrevs = v.lastrevs || v_w WHERE v.ctid = v_cur.tgsis_ctid_;
    END IF;
    RETURN OLD;
END
$body$$fn$,
        p_schema, p_table || '_ver_write', p_table, v_ver, v_cols, v_new_key, v_new, v_assign, v_visible, v_dup,
        (SELECT string_agg(format('NEW.%I', k), ', ' ORDER BY o) FROM unnest(p_keys) WITH ORDINALITY AS u(k, o)),
        (SELECT string_agg(format('OLD.%I', k), ', ' ORDER BY o) FROM unnest(p_keys) WITH ORDINALITY AS u(k, o)),
        v_old_key, p_class, p_keyfield, p_table || '_ver_pkey', v_current, v_same, v_stale);
END
$gen$;

COMMENT ON FUNCTION tgsis.versioning_trigger_source(text, text, text[], text[], text, text, text) IS
    'source of the INSTEAD OF INSERT/UPDATE/DELETE trigger function <table>_ver_write() that enable_versioning creates: writes on the row version current when locked, or 40001 when the statement read a row a concurrent transaction changed';

-- ==== versioning/enable_versioning_rel.sql ====
-- tgsis.enable_versioning_rel(table, objectkeyfield, objectclass, iudorder, shortname): version a table in place.
-- Called by tgsis.enable_versioning, which resolves the table name in the
-- caller's search_path; this one runs with a fixed search_path so that the
-- constraint definitions it records are schema-qualified.
-- The table's storage becomes <table>_ver (its columns plus revision and
-- lastrevs, primary key extended by revision) and a view <table> with the
-- original columns, defaults, comments and grants takes its place, so that
-- plain SELECT/INSERT/UPDATE/DELETE keep working, in the session's version.
-- Constraints that cannot hold across versions (foreign keys between
-- versioned tables, other unique keys) are dropped and recorded so that
-- disable_versioning can restore them.
CREATE FUNCTION tgsis.enable_versioning_rel(
    p_table          regclass,
    p_objectkeyfield text,
    p_objectclass    text,
    p_iudorder       integer DEFAULT 0,
    p_shortname      text    DEFAULT NULL)
RETURNS tgsis.versioned_tables
LANGUAGE plpgsql
VOLATILE
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_rel       regclass := p_table;
    v_schema    text;
    v_table     text;
    v_kind      "char";
    v_owner     oid;
    v_ver       text;
    v_pkey      text;
    v_keys      text[];
    v_columns   text[];
    v_writable  text[];
    v_dependent text;
    v_identity  text[];
    v_skip      text;
    v_relacl    aclitem[];
    v_name      text;
    v_comment   text := obj_description(p_table, 'pg_class');
    v_con       record;
    v_col       record;
    v_acl       record;
BEGIN
    SELECT n.nspname, c.relname, c.relkind, c.relowner INTO v_schema, v_table, v_kind, v_owner
      FROM pg_class c JOIN pg_namespace n ON n.oid = c.relnamespace WHERE c.oid = v_rel;
    IF EXISTS (SELECT FROM tgsis.versioned_tables WHERE schemaname = v_schema AND tablename = v_table) THEN
        RAISE EXCEPTION 'table %.% is versioned already', v_schema, v_table USING ERRCODE = 'TG201';
    END IF;
    IF v_kind <> 'r' THEN
        RAISE EXCEPTION '%.% is not an ordinary table: only ordinary tables can be versioned', v_schema, v_table
            USING ERRCODE = 'TG100',
                  DETAIL = format('Its kind is %s.', CASE v_kind WHEN 'v' THEN 'a view' WHEN 'm' THEN 'a materialized view'
                                                              WHEN 'p' THEN 'a partitioned table' WHEN 'f' THEN 'a foreign table'
                                                              ELSE v_kind::text END);
    END IF;
    -- in tgsis's schema only the registered storage of the data models
    IF v_schema = 'tgsis' AND NOT EXISTS (SELECT FROM tgsis.model_tables WHERE tablename = v_table) THEN
        RAISE EXCEPTION 'tgsis.% is part of tgsis''s own catalog and cannot be versioned', v_table USING ERRCODE = 'TG100';
    END IF;
    IF NOT pg_has_role(current_user, v_owner, 'USAGE') THEN
        RAISE EXCEPTION 'only the owner of %.% (%) may version it', v_schema, v_table, pg_get_userbyid(v_owner)
            USING ERRCODE = 'TG002';
    END IF;
    -- (its registration goes through definer helpers that only tgsis_admin may call)
    IF NOT pg_has_role(tgsis.calling_role(), 'tgsis_admin', 'MEMBER') THEN
        RAISE EXCEPTION 'role % may not version tables', tgsis.calling_role()
            USING ERRCODE = 'TG002', DETAIL = 'Versioning tables is for members of tgsis_admin that own them.',
                  HINT = format('a DBA may run: GRANT tgsis_admin TO %I', tgsis.calling_role());
    END IF;
    v_ver := v_table || '_ver';
    IF octet_length(v_table || '_ver_write') > 63 THEN
        RAISE EXCEPTION 'table name % is too long to be versioned', quote_literal(v_table)
            USING ERRCODE = 'TG101', DETAIL = 'Versioning adds <table>_ver and <table>_ver_write(), which must fit in 63 bytes.';
    END IF;
    IF to_regclass(format('%I.%I', v_schema, v_ver)) IS NOT NULL
       OR to_regprocedure(format('%I.%I()', v_schema, v_table || '_ver_write')) IS NOT NULL
       OR EXISTS (SELECT FROM pg_proc WHERE pronamespace = to_regnamespace(quote_ident(v_schema))
                                        AND proname = v_table || '_ver_run') THEN
        RAISE EXCEPTION '%.%, %.%() or %.%() exists already', v_schema, v_ver, v_schema, v_table || '_ver_write',
                v_schema, v_table || '_ver_run'
            USING ERRCODE = 'TG201', HINT = 'versioning needs these names for the table''s storage, trigger and runner';
    END IF;
    IF p_objectclass IS NULL OR btrim(p_objectclass) = '' OR p_iudorder IS NULL THEN
        RAISE EXCEPTION 'versioning %.% needs an object class and an iudorder', v_schema, v_table USING ERRCODE = 'TG100';
    END IF;
    IF EXISTS (SELECT FROM tgsis.versioned_tables
                WHERE objectclass = p_objectclass AND shortname = coalesce(p_shortname, v_table)) THEN
        RAISE EXCEPTION 'object class % has a table with short name % already', quote_literal(p_objectclass),
                quote_literal(coalesce(p_shortname, v_table))
            USING ERRCODE = 'TG201', HINT = 'pass another p_shortname';
    END IF;

    SELECT con.conname, array_agg(a.attname::text ORDER BY k.ord) INTO v_pkey, v_keys
      FROM pg_constraint con
      CROSS JOIN LATERAL unnest(con.conkey) WITH ORDINALITY AS k(attnum, ord)
      JOIN pg_attribute a ON a.attrelid = con.conrelid AND a.attnum = k.attnum
     WHERE con.conrelid = v_rel AND con.contype = 'p'
     GROUP BY con.conname;
    IF v_pkey IS NULL THEN
        RAISE EXCEPTION 'table %.% has no primary key', v_schema, v_table
            USING ERRCODE = 'TG100', HINT = 'versioning tells the rows of a table apart by its primary key: add one first';
    END IF;
    SELECT array_agg(attname::text ORDER BY attnum), array_agg(attname::text ORDER BY attnum) FILTER (WHERE attgenerated = '')
      INTO v_columns, v_writable
      FROM pg_attribute WHERE attrelid = v_rel AND attnum > 0 AND NOT attisdropped;
    IF v_columns && ARRAY['revision', 'lastrevs', 'revclosed'] THEN
        RAISE EXCEPTION 'table %.% has a column named revision, lastrevs or revclosed, which versioning needs', v_schema, v_table
            USING ERRCODE = 'TG100', HINT = 'rename the column first';
    END IF;
    IF p_objectkeyfield IS NULL OR NOT p_objectkeyfield = ANY (v_columns) THEN
        RAISE EXCEPTION 'table %.% has no column % to hold the object key', v_schema, v_table,
                coalesce(quote_literal(p_objectkeyfield), 'NULL')
            USING ERRCODE = 'TG200', DETAIL = format('Its columns: %s.', array_to_string(v_columns, ', '));
    END IF;
    -- keys are cast to and from text by tgsis's definer code: with a type of
    -- its own (a domain's check, a cast) the table's owner would run code there
    IF (SELECT atttypid FROM pg_attribute WHERE attrelid = v_rel AND attname = p_objectkeyfield) >= 16384 THEN
        RAISE EXCEPTION 'the object key column % of %.% is of type %, which is not built into PostgreSQL', p_objectkeyfield,
                v_schema, v_table, (SELECT format_type(atttypid, atttypmod) FROM pg_attribute
                                     WHERE attrelid = v_rel AND attname = p_objectkeyfield)
            USING ERRCODE = 'TG100',
                  DETAIL = 'tgsis''s own functions read and compare object keys as tgsis''s owner; a type of one''s own could run its owner''s code there.',
                  HINT = 'key the objects by a column of a built-in type (integer, bigint, text, uuid, ...)';
    END IF;

    -- views and rules reading the table would read every row version afterwards
    SELECT string_agg(DISTINCT r.ev_class::regclass::text, ', ') INTO v_dependent
      FROM pg_depend d JOIN pg_rewrite r ON d.classid = 'pg_rewrite'::regclass AND d.objid = r.oid
     WHERE d.refclassid = 'pg_class'::regclass AND d.refobjid = v_rel AND r.ev_class <> v_rel;
    IF v_dependent IS NOT NULL THEN
        RAISE EXCEPTION 'views depend on %.%: %', v_schema, v_table, v_dependent
            USING ERRCODE = 'TG202', HINT = 'drop them, enable versioning, then create them again: they will read the versioned view';
    END IF;
    -- foreign keys into the table from plain tables cannot follow it
    SELECT string_agg(format('%s (%s)', con.conrelid::regclass, con.conname), ', ') INTO v_dependent
      FROM pg_constraint con
     WHERE con.confrelid = v_rel AND con.contype = 'f' AND con.conrelid <> v_rel
       AND NOT EXISTS (SELECT FROM tgsis.versioned_tables t JOIN pg_class c ON c.relname = t.tablename || '_ver'
                         JOIN pg_namespace n ON n.oid = c.relnamespace AND n.nspname = t.schemaname
                        WHERE c.oid = con.conrelid);
    IF v_dependent IS NOT NULL THEN
        RAISE EXCEPTION 'foreign keys of plain tables refer to %.%: %', v_schema, v_table, v_dependent
            USING ERRCODE = 'TG202', HINT = 'version those tables too (their keys are then dropped), or drop the constraints';
    END IF;

    -- what cannot hold across versions: foreign keys to versioned tables (and
    -- from them into this one), self references, unique keys other than the
    -- primary key, exclusion constraints
    FOR v_con IN
        SELECT con.oid, con.conname, con.conrelid, con.confrelid
          FROM pg_constraint con
         WHERE (con.conrelid = v_rel AND con.contype IN ('u', 'x'))
            OR (con.contype = 'f' AND (con.confrelid = v_rel OR (con.conrelid = v_rel AND (
                    con.confrelid = v_rel OR EXISTS (
                        SELECT FROM tgsis.versioned_tables t JOIN pg_class c ON c.relname = t.tablename || '_ver'
                          JOIN pg_namespace n ON n.oid = c.relnamespace AND n.nspname = t.schemaname
                         WHERE c.oid = con.confrelid)))))
         ORDER BY con.contype, con.conname
    LOOP
        -- a key of another versioned table into this one: only that table's owner may drop it
        IF NOT pg_has_role(current_user, (SELECT relowner FROM pg_class WHERE oid = v_con.conrelid), 'USAGE') THEN
            RAISE EXCEPTION 'foreign key % of % refers to %.%, and role % may not drop it', v_con.conname,
                    v_con.conrelid::regclass, v_schema, v_table, current_user
                USING ERRCODE = 'TG002',
                      DETAIL = 'Keys between versioned tables cannot hold across versions; versioning drops them.',
                      HINT = format('the owner of %s may drop the key, or make that table plain and drop it there', v_con.conrelid::regclass);
        END IF;
        PERFORM tgsis.record_dropped(v_rel, v_con.oid);  -- its definition, read from the catalogs
        EXECUTE format('ALTER TABLE %s DROP CONSTRAINT %I', v_con.conrelid::regclass, v_con.conname);
    END LOOP;
    FOR v_con IN
        SELECT c.relname::text AS idx, i.indexrelid
          FROM pg_index i JOIN pg_class c ON c.oid = i.indexrelid
         WHERE i.indrelid = v_rel AND i.indisunique
           AND NOT EXISTS (SELECT FROM pg_constraint con WHERE con.conindid = i.indexrelid)
    LOOP
        PERFORM tgsis.record_dropped(v_rel, v_con.indexrelid, true);
        EXECUTE format('DROP INDEX %I.%I', v_schema, v_con.idx);
    END LOOP;
    SELECT coalesce(array_agg(attname::text ORDER BY attnum), '{}') INTO v_identity
      FROM pg_attribute WHERE attrelid = v_rel AND attnum > 0 AND NOT attisdropped AND attidentity = 'a';

    -- storage
    EXECUTE format('ALTER TABLE %I.%I RENAME TO %I', v_schema, v_table, v_ver);
    FOREACH v_name IN ARRAY v_identity LOOP
        EXECUTE format('ALTER TABLE %I.%I ALTER COLUMN %I SET GENERATED BY DEFAULT', v_schema, v_ver, v_name);
    END LOOP;
    EXECUTE format('ALTER TABLE %I.%I ADD COLUMN revision integer NOT NULL DEFAULT 0, '
                   'ADD COLUMN lastrevs integer[] NOT NULL DEFAULT ''{}'', '
                   -- a plain flag the view tests before lastrevs: reading an array
                   -- copies it out of the row, and almost every row is live
                   'ADD COLUMN revclosed boolean GENERATED ALWAYS AS (cardinality(lastrevs) > 0) STORED', v_schema, v_ver);
    -- existing rows are revision 0: DEFAULT's first revision, in every version's set
    EXECUTE format('ALTER TABLE %I.%I ALTER COLUMN revision DROP DEFAULT', v_schema, v_ver);
    EXECUTE format('ALTER TABLE %I.%I DROP CONSTRAINT %I', v_schema, v_ver, v_pkey);
    EXECUTE format('ALTER TABLE %I.%I ADD CONSTRAINT %I PRIMARY KEY (%s, revision)', v_schema, v_ver, v_ver || '_pkey',
                   (SELECT string_agg(format('%I', k), ', ' ORDER BY o) FROM unnest(v_keys) WITH ORDINALITY AS u(k, o)));
    IF v_keys[1] <> p_objectkeyfield THEN
        EXECUTE format('CREATE INDEX %I ON %I.%I (%I, revision)', v_ver || '_object_idx', v_schema, v_ver, p_objectkeyfield);
    END IF;
    EXECUTE format('COMMENT ON TABLE %I.%I IS %L', v_schema, v_ver,
                   format('row versions of %s.%s (tgsis versioning): read and write it through the view %s.%s',
                          v_schema, v_table, v_schema, v_table));
    EXECUTE format('COMMENT ON COLUMN %I.%I.revision IS %L', v_schema, v_ver, 'revision in which this row version was written');
    EXECUTE format('COMMENT ON COLUMN %I.%I.revclosed IS %L', v_schema, v_ver,
                   'lastrevs is not empty (kept by PostgreSQL): lets reads skip the array for live rows');
    EXECUTE format('COMMENT ON COLUMN %I.%I.lastrevs IS %L', v_schema, v_ver,
                   'revisions in which this row version stopped being current (updated or deleted there); empty while live');

    -- storage keeps the table's SELECT and INSERT grants, for the client's bulk path (COPY upload); rows are
    -- changed and closed only through the view and tgsis's functions, so no other role may update or delete
    -- them (disable_versioning gives the grants back from the view's)
    SELECT relacl INTO v_relacl FROM pg_class WHERE oid = v_rel;  -- the view gets them all, below
    FOR v_acl IN
        SELECT DISTINCT a.grantee FROM aclexplode(v_relacl) AS a
         WHERE a.grantee <> v_owner
           AND a.privilege_type IN ('UPDATE', 'DELETE', 'TRUNCATE', 'REFERENCES', 'TRIGGER')
    LOOP
        EXECUTE format('REVOKE UPDATE, DELETE, TRUNCATE, REFERENCES, TRIGGER ON %I.%I FROM %s', v_schema, v_ver,
                       CASE WHEN v_acl.grantee = 0 THEN 'PUBLIC' ELSE quote_ident(pg_get_userbyid(v_acl.grantee)) END);
    END LOOP;
    -- direct writers need the version's write right and may only add live rows of its working revision
    -- (not the table's owner, as whom the view's row trigger writes, nor tgsis's, as whom merges write:
    -- the WHEN spares them a call per statement)
    -- (by role name, not oid: a dump restored into another cluster keeps the names, not the oids)
    v_skip := format('NOT pg_catalog.pg_has_role(current_user, %L::name, ''USAGE'') '
                     'AND NOT pg_catalog.pg_has_role(current_user, %L::name, ''USAGE'')',
                     pg_get_userbyid(v_owner), (SELECT pg_get_userbyid(nspowner) FROM pg_namespace WHERE nspname = 'tgsis'));
    EXECUTE format('CREATE TRIGGER tgsis_storage_write BEFORE INSERT OR UPDATE OR DELETE OR TRUNCATE ON %I.%I '
                   'FOR EACH STATEMENT WHEN (%s) EXECUTE FUNCTION tgsis.storage_write_check()', v_schema, v_ver, v_skip);
    EXECUTE format('CREATE TRIGGER tgsis_storage_rows AFTER INSERT ON %I.%I REFERENCING NEW TABLE AS tgsis_new_rows '
                   'FOR EACH STATEMENT WHEN (%s) EXECUTE FUNCTION tgsis.storage_rows_check(%L, %L)',
                   v_schema, v_ver, v_skip, p_objectclass, p_objectkeyfield);

    -- the view in the table's place, with its defaults, comments, grants and owner
    EXECUTE tgsis.versioned_view_source(v_schema, v_table, v_columns);
    FOR v_col IN
        SELECT a.attname,
               CASE WHEN a.attidentity <> '' THEN format('nextval(%L::regclass)', pg_get_serial_sequence(v_rel::text, a.attname))
                    ELSE pg_get_expr(d.adbin, d.adrelid) END AS expr,
               col_description(v_rel, a.attnum) AS note
          FROM pg_attribute a LEFT JOIN pg_attrdef d ON d.adrelid = a.attrelid AND d.adnum = a.attnum
         WHERE a.attrelid = v_rel AND a.attnum > 0 AND NOT a.attisdropped AND a.attname::text = ANY (v_columns)
    LOOP
        IF v_col.expr IS NOT NULL AND v_col.attname::text = ANY (v_writable) THEN
            -- a deparsed default from the catalog: SQL text, not a value to quote
            EXECUTE format('ALTER VIEW %I.%I ALTER COLUMN %I SET DEFAULT %s', v_schema, v_table, v_col.attname, v_col.expr);
        END IF;
        IF v_col.note IS NOT NULL THEN
            EXECUTE format('COMMENT ON COLUMN %I.%I.%I IS %L', v_schema, v_table, v_col.attname, v_col.note);
        END IF;
    END LOOP;
    EXECUTE format('COMMENT ON VIEW %I.%I IS %L', v_schema, v_table,
                   coalesce(v_comment || ' ', '')
                   || format('(versioned by tgsis: rows of the session''s version; storage %s)', v_ver));
    FOR v_acl IN
        SELECT a.privilege_type, a.grantee FROM aclexplode(v_relacl) AS a WHERE a.grantee <> v_owner
    LOOP
        EXECUTE format('GRANT %s ON %I.%I TO %s', v_acl.privilege_type, v_schema, v_table,
                       CASE WHEN v_acl.grantee = 0 THEN 'PUBLIC' ELSE quote_ident(pg_get_userbyid(v_acl.grantee)) END);
    END LOOP;
    EXECUTE tgsis.versioning_trigger_source(v_schema, v_table, v_keys, v_writable, v_pkey, p_objectclass, p_objectkeyfield);
    EXECUTE format('COMMENT ON FUNCTION %I.%I() IS %L', v_schema, v_table || '_ver_write',
                   format('tgsis versioning: INSTEAD OF trigger routing writes on %s.%s into %s', v_schema, v_table, v_ver));
    EXECUTE format('CREATE TRIGGER %I INSTEAD OF INSERT OR UPDATE OR DELETE ON %I.%I FOR EACH ROW EXECUTE FUNCTION %I.%I()',
                   'tgsis_versioning', v_schema, v_table, v_schema, v_table || '_ver_write');
    EXECUTE format('CREATE TRIGGER tgsis_versioning_rights BEFORE INSERT OR UPDATE OR DELETE ON %I.%I '
                   'FOR EACH STATEMENT EXECUTE FUNCTION tgsis.view_write_check()', v_schema, v_table);
    EXECUTE format('ALTER VIEW %I.%I OWNER TO %I', v_schema, v_table, pg_get_userbyid(v_owner));
    EXECUTE format('ALTER FUNCTION %I.%I() OWNER TO %I', v_schema, v_table || '_ver_write', pg_get_userbyid(v_owner));
    EXECUTE format('REVOKE ALL ON FUNCTION %I.%I() FROM PUBLIC', v_schema, v_table || '_ver_write');
    -- through which tgsis's definer code acts on the storage, as its owner
    PERFORM tgsis.create_storage_runner(v_schema, v_table);

    -- recorded by tgsis's definer helper, which checks what it records against the catalogs
    RETURN tgsis.register_versioned_table(format('%I.%I', v_schema, v_table)::regclass, p_objectkeyfield, p_objectclass,
                                          p_iudorder, p_shortname, v_pkey, v_comment, v_identity);
END
$$;

COMMENT ON FUNCTION tgsis.enable_versioning_rel(regclass, text, text, integer, text) IS
    'the work of tgsis.enable_versioning on a resolved table: version a table: storage renamed <table>_ver (+ revision, lastrevs, revclosed), a view <table> with INSTEAD OF triggers takes its place; registered in tgsis.versioned_tables';

-- ==== versioning/enable_versioning.sql ====
-- tgsis.enable_versioning(table, objectkeyfield, objectclass, iudorder, shortname): version a table in place.
-- The table (name or schema.name, found in the caller's search_path) keeps
-- its name and columns for applications: see tgsis.enable_versioning_rel.
CREATE FUNCTION tgsis.enable_versioning(
    p_table          text,
    p_objectkeyfield text,
    p_objectclass    text,
    p_iudorder       integer DEFAULT 0,
    p_shortname      text    DEFAULT NULL)
RETURNS tgsis.versioned_tables
LANGUAGE plpgsql
VOLATILE
AS $$
BEGIN
    RETURN tgsis.enable_versioning_rel(tgsis.resolve_table(p_table), p_objectkeyfield, p_objectclass, p_iudorder, p_shortname);
END
$$;

COMMENT ON FUNCTION tgsis.enable_versioning(text, text, text, integer, text) IS
    'version a table: storage renamed <table>_ver (+ revision, lastrevs), a view <table> with INSTEAD OF triggers takes its place; registered in tgsis.versioned_tables';

-- ==== versioning/restore_dropped_constraints.sql ====
-- tgsis.restore_dropped_constraints(schema, table): re-create the dropped constraints of, or referring to, a table just made plain; returns how many.
-- Called by disable_versioning_rel, as the role making the table plain
-- (tgsis's owner within disable_feature_versioning). It restores only rows
-- about that table whose tables are all plain again; the definitions are
-- system-catalog text that tgsis.record_dropped (or tgsis's own definer code)
-- wrote, as nobody else may write tgsis.versioning_dropped. A constraint that
-- exists already is only forgotten; one on a table the role may not alter
-- stays recorded (NOTICE) for its owner's disable_versioning to restore.
CREATE FUNCTION tgsis.restore_dropped_constraints(p_schema text, p_table text)
RETURNS integer
LANGUAGE plpgsql
VOLATILE
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_item  tgsis.versioning_dropped;
    v_rel   regclass;
    v_count integer := 0;
BEGIN
    FOR v_item IN
        SELECT d.* FROM tgsis.versioning_dropped d
         WHERE ((d.schemaname = p_schema AND d.tablename = p_table) OR (d.refschema = p_schema AND d.reftable = p_table))
           AND NOT EXISTS (SELECT FROM tgsis.versioned_tables t
                            WHERE (t.schemaname, t.tablename) IN ((d.schemaname, d.tablename), (d.refschema, d.reftable)))
         ORDER BY d.is_index DESC, d.id  -- unique indexes first: foreign keys may need them
    LOOP
        IF tgsis.forget_dropped(v_item.id) THEN
            CONTINUE;  -- it is there (recorded but never dropped)
        END IF;
        v_rel := to_regclass(format('%I.%I', v_item.schemaname, v_item.tablename));
        IF v_rel IS NULL OR NOT pg_has_role(current_user, (SELECT relowner FROM pg_class WHERE oid = v_rel), 'USAGE') THEN
            RAISE NOTICE 'constraint % of %.% stays dropped: role % may not alter that table',
                    v_item.name, v_item.schemaname, v_item.tablename, current_user
                USING HINT = 'its owner restores it with tgsis.restore_dropped_constraints(schema, table)';
            CONTINUE;
        END IF;
        IF v_item.is_index THEN
            EXECUTE v_item.definition;  -- pg_get_indexdef text: a complete, qualified statement
        ELSE
            EXECUTE format('ALTER TABLE %I.%I ADD CONSTRAINT %I %s', v_item.schemaname, v_item.tablename, v_item.name,
                           v_item.definition);
        END IF;
        PERFORM tgsis.forget_dropped(v_item.id);
        v_count := v_count + 1;
    END LOOP;
    RETURN v_count;
END
$$;

COMMENT ON FUNCTION tgsis.restore_dropped_constraints(text, text) IS
    're-create the constraints and unique indexes dropped by enable_versioning that belong to or refer to a table made plain again, once all their tables are plain; returns how many';

-- ==== versioning/disable_versioning_rel.sql ====
-- tgsis.disable_versioning_rel(view, force): the work of tgsis.disable_versioning on a resolved view.
-- Refuses while versions other than DEFAULT have changes in it (they would be
-- lost) unless forced.
CREATE FUNCTION tgsis.disable_versioning_rel(p_table regclass, p_force boolean DEFAULT false)
RETURNS bigint
LANGUAGE plpgsql
VOLATILE
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_t         tgsis.versioned_tables := tgsis.versioned_table(p_table);
    v_view      regclass;
    v_ver       text := v_t.tablename || '_ver';
    v_default   integer[];
    v_dependent text;
    v_name      text;
    v_removed   bigint;
    v_acl       record;
BEGIN
    v_view := format('%I.%I', v_t.schemaname, v_t.tablename)::regclass;
    IF NOT pg_has_role(current_user, (SELECT relowner FROM pg_class WHERE oid = v_view), 'USAGE') THEN
        RAISE EXCEPTION 'only the owner of %.% may stop versioning it', v_t.schemaname, v_t.tablename USING ERRCODE = 'TG002';
    END IF;
    SELECT string_agg(DISTINCT r.ev_class::regclass::text, ', ') INTO v_dependent
      FROM pg_depend d JOIN pg_rewrite r ON d.classid = 'pg_rewrite'::regclass AND d.objid = r.oid
     WHERE d.refclassid = 'pg_class'::regclass AND d.refobjid = v_view AND r.ev_class <> v_view;
    IF v_dependent IS NOT NULL THEN
        RAISE EXCEPTION 'views depend on %.%: %', v_t.schemaname, v_t.tablename, v_dependent
            USING ERRCODE = 'TG202', HINT = 'drop them first and create them again afterwards';
    END IF;
    SELECT workingset INTO v_default FROM tgsis.versions WHERE versionid = 0;
    IF NOT coalesce(p_force, false) THEN
        EXECUTE format('SELECT string_agg(DISTINCT x.name, '', '') FROM %I.%I v, tgsis.revisions r, tgsis.versions x
                         WHERE x.versionid = r.versionid AND r.versionid <> 0
                           AND (r.revision = v.revision OR r.revision = ANY (v.lastrevs))', v_t.schemaname, v_ver)
           INTO v_dependent;
        IF v_dependent IS NOT NULL THEN
            RAISE EXCEPTION 'versions other than DEFAULT changed %.%: %', v_t.schemaname, v_t.tablename, v_dependent
                USING ERRCODE = 'TG202',
                      DETAIL = 'Only the rows DEFAULT sees now are kept; those changes would be lost.',
                      HINT = 'merge or delete those versions first, or pass p_force => true';
        END IF;
    END IF;

    -- the rights storage did not keep (updates and deletes went through the view) come back from the view
    FOR v_acl IN
        SELECT a.privilege_type, a.grantee FROM pg_class c, aclexplode(c.relacl) AS a
         WHERE c.oid = v_view AND a.grantee <> c.relowner
           AND a.privilege_type IN ('UPDATE', 'DELETE', 'TRUNCATE', 'REFERENCES', 'TRIGGER')
    LOOP
        EXECUTE format('GRANT %s ON %I.%I TO %s', v_acl.privilege_type, v_t.schemaname, v_ver,
                       CASE WHEN v_acl.grantee = 0 THEN 'PUBLIC' ELSE quote_ident(pg_get_userbyid(v_acl.grantee)) END);
    END LOOP;
    EXECUTE format('DROP VIEW %I.%I', v_t.schemaname, v_t.tablename);
    EXECUTE format('DROP FUNCTION %I.%I()', v_t.schemaname, v_t.tablename || '_ver_write');
    EXECUTE format('DROP FUNCTION IF EXISTS %I.%I(boolean, text, text[], integer[], integer[], integer, bigint[])',
                   v_t.schemaname, v_t.tablename || '_ver_run');
    EXECUTE format('DELETE FROM %I.%I v WHERE NOT (v.revision = ANY ($1) AND NOT (v.lastrevs && $1))', v_t.schemaname, v_ver)
      USING v_default;
    GET DIAGNOSTICS v_removed = ROW_COUNT;
    EXECUTE format('DROP TRIGGER tgsis_storage_write ON %I.%I', v_t.schemaname, v_ver);
    EXECUTE format('DROP TRIGGER tgsis_storage_rows ON %I.%I', v_t.schemaname, v_ver);
    EXECUTE format('ALTER TABLE %I.%I DROP CONSTRAINT %I', v_t.schemaname, v_ver, v_ver || '_pkey');
    EXECUTE format('ALTER TABLE %I.%I DROP COLUMN revision, DROP COLUMN revclosed, DROP COLUMN lastrevs', v_t.schemaname, v_ver);
    EXECUTE format('ALTER TABLE %I.%I RENAME TO %I', v_t.schemaname, v_ver, v_t.tablename);
    EXECUTE format('ALTER TABLE %I.%I ADD CONSTRAINT %I PRIMARY KEY (%s)', v_t.schemaname, v_t.tablename, v_t.pkeyname,
                   (SELECT string_agg(format('%I', k), ', ' ORDER BY o) FROM unnest(v_t.keycolumns) WITH ORDINALITY AS u(k, o)));
    FOREACH v_name IN ARRAY v_t.identity_always LOOP
        EXECUTE format('ALTER TABLE %I.%I ALTER COLUMN %I SET GENERATED ALWAYS', v_t.schemaname, v_t.tablename, v_name);
    END LOOP;
    EXECUTE format('COMMENT ON TABLE %I.%I IS %L', v_t.schemaname, v_t.tablename, v_t.tablecomment);
    PERFORM tgsis.unregister_versioned_table(v_t.schemaname, v_t.tablename);
    PERFORM tgsis.restore_dropped_constraints(v_t.schemaname, v_t.tablename);
    RETURN v_removed;
END
$$;

COMMENT ON FUNCTION tgsis.disable_versioning_rel(regclass, boolean) IS
    'the work of tgsis.disable_versioning on a resolved view: make a versioned table plain again with the rows DEFAULT sees (refused while other versions changed it, unless p_force); restores dropped constraints; returns the row versions removed';

-- ==== versioning/disable_versioning.sql ====
-- tgsis.disable_versioning(table, force): turn a versioned table back into a plain one holding DEFAULT's current rows.
-- Refuses while versions other than DEFAULT have changes in it (they would be
-- lost) unless forced; see tgsis.disable_versioning_rel.
CREATE FUNCTION tgsis.disable_versioning(p_table text, p_force boolean DEFAULT false)
RETURNS bigint
LANGUAGE plpgsql
VOLATILE
AS $$
BEGIN
    RETURN tgsis.disable_versioning_rel(tgsis.resolve_table(p_table), p_force);
END
$$;

COMMENT ON FUNCTION tgsis.disable_versioning(text, boolean) IS
    'make a versioned table plain again with the rows DEFAULT sees (refused while other versions changed it, unless p_force); restores dropped constraints; returns the row versions removed';

-- ==== versioning/update_shared_rows.sql ====
-- tgsis.update_shared_rows(table, set, condition, $1, $2, $3, $4): UPDATE rows other versions' writers may hold, never waiting while holding some; returns the rows updated.
-- A stored row of a version is shared by every version that sees it: the
-- children of a parent all see its rows, and writers in each of them close
-- those rows (append to lastrevs) in their own revisions, row by row in the
-- order of their statements. Merge, refresh and delete_version change such
-- rows for many at once, locking only the versions they involve. Had their
-- UPDATE waited for one row while holding others, a writer elsewhere wanting
-- one of those would deadlock with it (40P01; tests/test_concurrency.py). So
-- the UPDATE never waits (a 1 ms lock_timeout undoes it as a whole), and
-- when a row is taken, its holder is waited for with no row lock held (under
-- the caller's lock_timeout), then the UPDATE is tried again.
-- p_set and p_where are SQL over the alias v of the table's storage and the
-- parameters $1 text[], $2 integer[], $3 integer[], $4 integer; every
-- statement runs through tgsis.storage_run (as the storage's owner).
CREATE FUNCTION tgsis.update_shared_rows(
    p_t     tgsis.versioned_tables,
    p_set   text,
    p_where text,
    p_1     text[],
    p_2     integer[],
    p_3     integer[],
    p_4     integer)
RETURNS bigint
LANGUAGE plpgsql
VOLATILE
AS $$
DECLARE
    v_table   text := format('%I.%I', p_t.schemaname, p_t.tablename || '_ver');
    v_count   bigint;
    v_busy    text;
    v_timeout text := current_setting('lock_timeout');
    v_undo    CONSTANT text := 'tgsis: undo the row locks of this block';
BEGIN
    LOOP
        BEGIN
            PERFORM set_config('lock_timeout', '1ms', true);
            SELECT r[1]::bigint INTO v_count
              FROM tgsis.storage_run(p_t, true, format('UPDATE %s v SET %s WHERE %s', v_table, p_set, p_where),
                                     p_1, p_2, p_3, p_4) AS r;
            PERFORM set_config('lock_timeout', v_timeout, true);
            RETURN v_count;
        EXCEPTION WHEN lock_not_available THEN
            NULL;   -- the block's row locks, changes and setting are undone
        END;
        -- a row another transaction holds: one the UPDATE would change that
        -- cannot be locked now (found in a block then undone: none stays locked)
        v_busy := NULL;
        BEGIN
            SELECT r[1] INTO v_busy
              FROM tgsis.storage_run(p_t, false, format(
                       'SELECT ARRAY[b.ctid::text] FROM (SELECT v.ctid FROM %1$s v WHERE %2$s EXCEPT
                                SELECT f.ctid FROM (SELECT v.ctid FROM %1$s v WHERE %2$s FOR UPDATE SKIP LOCKED) f
                                LIMIT 1) b', v_table, p_where), p_1, p_2, p_3, p_4) AS r;
            RAISE EXCEPTION USING MESSAGE = v_undo;
        EXCEPTION WHEN OTHERS THEN
            IF SQLERRM IS DISTINCT FROM v_undo THEN
                RAISE;
            END IF;
        END;
        IF v_busy IS NOT NULL THEN
            -- wait for its holder, then let go of the row again
            BEGIN
                PERFORM FROM tgsis.storage_run(p_t, false, format(
                    'SELECT ARRAY[]::text[] FROM %s v WHERE v.ctid = ($1[1])::tid FOR UPDATE', v_table), ARRAY[v_busy]);
                RAISE EXCEPTION USING MESSAGE = v_undo;
            EXCEPTION WHEN OTHERS THEN
                IF SQLERRM IS DISTINCT FROM v_undo THEN
                    RAISE;
                END IF;
            END;
        END IF;
    END LOOP;
END
$$;

COMMENT ON FUNCTION tgsis.update_shared_rows(tgsis.versioned_tables, text, text, text[], integer[], integer[], integer) IS
    'UPDATE <table>_ver v SET p_set WHERE p_where ($1..$4 = p_1..p_4) without ever waiting for a row while holding others, so that it cannot deadlock with writers of other versions that see the same stored rows; returns the rows updated';

-- ==== versioning/delete_version.sql ====
-- tgsis.delete_version(name): remove a leaf version, its revisions and its row versions; returns the rows removed.
CREATE FUNCTION tgsis.delete_version(p_name text)
RETURNS bigint
LANGUAGE plpgsql
VOLATILE
SECURITY DEFINER
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_id       integer := tgsis.version_id(p_name);
    v_children text;
    v_revs     integer[];
    v_t        tgsis.versioned_tables;
    v_count    bigint;
    v_removed  bigint := 0;
BEGIN
    IF v_id = 0 THEN
        RAISE EXCEPTION 'version DEFAULT cannot be deleted' USING ERRCODE = 'TG100', DETAIL = 'It is the root of the version tree.';
    END IF;
    PERFORM tgsis.require_version_privilege(v_id, 'delete', 'delete');
    PERFORM FROM tgsis.versions WHERE versionid = v_id FOR UPDATE;
    IF NOT FOUND THEN
        -- deleted (or merged away) by the transaction this one waited for:
        -- say so rather than report 0 rows removed
        RAISE EXCEPTION 'version % does not exist', quote_literal(p_name)
            USING ERRCODE = 'TG200', DETAIL = 'It was deleted while this delete_version waited for it.';
    END IF;
    SELECT string_agg(quote_literal(name), ', ' ORDER BY name) INTO v_children FROM tgsis.versions WHERE parentid = v_id;
    IF v_children IS NOT NULL THEN
        RAISE EXCEPTION 'version % has child versions: %', quote_literal(p_name), v_children
            USING ERRCODE = 'TG202', HINT = 'delete (or merge) the children first';
    END IF;
    SELECT array_agg(revision ORDER BY revision) INTO v_revs FROM tgsis.revisions WHERE versionid = v_id;
    FOR v_t IN SELECT * FROM tgsis.versioned_tables ORDER BY iudorder DESC, schemaname, tablename LOOP
        -- as the storage's owner (tgsis.storage_run)
        SELECT r[1]::bigint INTO v_count FROM tgsis.storage_run(v_t, true, format(
            'DELETE FROM %I.%I WHERE revision = ANY ($2)', v_t.schemaname, v_t.tablename || '_ver'), p_2 => v_revs) AS r;
        v_removed := v_removed + v_count;
        -- rows of ancestors that the version closed become live again for nobody else: drop its revisions
        -- (rows that sibling versions see too: changed without waiting for one while holding others)
        PERFORM tgsis.update_shared_rows(v_t,
                                         'lastrevs = ARRAY(SELECT r FROM unnest(v.lastrevs) AS r WHERE r <> ALL ($2))',
                                         'v.lastrevs && $2', NULL, v_revs, NULL, NULL);
    END LOOP;
    DELETE FROM tgsis.versions WHERE versionid = v_id;  -- its revisions go with it
    IF tgsis.get_working_version() = p_name THEN
        PERFORM set_config('tgsis.version', '', false);
        PERFORM set_config('tgsis.revision', '', false);
    END IF;
    RETURN v_removed;
END
$$;

COMMENT ON FUNCTION tgsis.delete_version(text) IS
    'delete a version without children: its revisions, the row versions written in them, and its revisions in other rows'' lastrevs; returns the row versions removed';

-- ==== versioning/own_working_revisions.sql ====
-- tgsis.own_working_revisions(versionid): the version's own revisions in its working set, ascending.
-- These hold its changes not yet merged: a merge re-bases the version and leaves the older ones behind.
CREATE FUNCTION tgsis.own_working_revisions(p_versionid integer)
RETURNS integer[]
LANGUAGE sql
STABLE
AS $$
    SELECT coalesce(array_agg(r.revision ORDER BY r.revision), '{}')
      FROM tgsis.revisions r JOIN tgsis.versions v ON v.versionid = r.versionid
     WHERE r.versionid = p_versionid AND r.revision = ANY (v.workingset)
$$;

COMMENT ON FUNCTION tgsis.own_working_revisions(integer) IS
    'a version''s own revisions in its working set (its changes since its base), ascending';

-- ==== versioning/conflicts.sql ====
-- Conflicting objects of versions (the thesis' CONFLICT table): objects
-- changed both in a version and in its parent since the version's base.
-- A solution holds for the state it was given on: find_conflicts sets it
-- back to 'unsolved' when either side changes the object again (the marks).
CREATE TABLE tgsis.conflicts (
    versionid    integer     NOT NULL REFERENCES tgsis.versions (versionid) ON DELETE CASCADE,
    objectclass  text        NOT NULL,
    objectkey    text        NOT NULL,
    conflicttype text[]      NOT NULL,
    childtables  text[]      NOT NULL,
    parenttables text[]      NOT NULL,
    childmark    text        NOT NULL,
    parentmark   text        NOT NULL,
    solution     text        NOT NULL DEFAULT 'unsolved'
                             CHECK (solution IN ('unsolved', 'parent', 'child', 'manual')),
    detected_at  timestamptz NOT NULL DEFAULT now(),
    solved_at    timestamptz,
    solved_by    name,
    PRIMARY KEY (versionid, objectclass, objectkey),
    CONSTRAINT conflicts_solved CHECK ((solution = 'unsolved') = (solved_at IS NULL))
);

COMMENT ON TABLE tgsis.conflicts IS
    'objects changed both in a version and in its parent since the version''s base, with their solutions (tgsis.find_conflicts, tgsis.resolve_conflict)';
COMMENT ON COLUMN tgsis.conflicts.versionid IS 'the child version';
COMMENT ON COLUMN tgsis.conflicts.objectclass IS 'object class of the object';
COMMENT ON COLUMN tgsis.conflicts.objectkey IS 'object key (as text)';
COMMENT ON COLUMN tgsis.conflicts.conflicttype IS 'short names of the tables changed on both sides (empty: the sides changed different tables of the object)';
COMMENT ON COLUMN tgsis.conflicts.childtables IS 'short names of the tables the version changed';
COMMENT ON COLUMN tgsis.conflicts.parenttables IS 'short names of the tables the parent changed';
COMMENT ON COLUMN tgsis.conflicts.childmark IS 'fingerprint of the version''s changes to the object (a later change unsolves the conflict)';
COMMENT ON COLUMN tgsis.conflicts.parentmark IS 'fingerprint of the parent''s changes to the object (a later change unsolves the conflict)';
COMMENT ON COLUMN tgsis.conflicts.solution IS 'unsolved, parent (keep the parent''s object), child (take the version''s), manual (the version holds a merged object)';
COMMENT ON COLUMN tgsis.conflicts.detected_at IS 'when the conflict was first found';
COMMENT ON COLUMN tgsis.conflicts.solved_at IS 'when the solution was recorded';
COMMENT ON COLUMN tgsis.conflicts.solved_by IS 'role that recorded it';

-- ==== versioning/changed_objects.sql ====
-- tgsis.changed_objects(revisions): objects with rows written or closed in any of the given revisions, per table.
-- One scan of each versioned table's storage.
CREATE FUNCTION tgsis.changed_objects(p_revisions integer[])
RETURNS TABLE (objectclass text, objectkey text, shortname text, mark text)
LANGUAGE plpgsql
VOLATILE
AS $$
DECLARE
    v_t tgsis.versioned_tables;
BEGIN
    IF cardinality(p_revisions) = 0 THEN
        RETURN;
    END IF;
    FOR v_t IN SELECT * FROM tgsis.versioned_tables ORDER BY objectclass, iudorder, shortname LOOP
        -- mark: a fingerprint of the object's changed row versions, so that
        -- any later write to them (even in the same revision) shows; the row
        -- as record_out writes it (v::text would call a cast the row type's
        -- owner may have created); read as the storage's owner from definer code
        RETURN QUERY SELECT v_t.objectclass, r[1], v_t.shortname, r[2] FROM tgsis.storage_run(v_t, false, format(
            'SELECT ARRAY[v.%I::text, md5(string_agg(pg_catalog.record_out(v.*)::text, ''|'' ORDER BY %s, v.revision))]
               FROM %I.%I v
              WHERE v.revision = ANY ($2) OR v.lastrevs && $2
              GROUP BY v.%I',
            v_t.objectkeyfield,
            (SELECT string_agg(format('v.%I', k), ', ' ORDER BY o) FROM unnest(v_t.keycolumns) WITH ORDINALITY AS u(k, o)),
            v_t.schemaname, v_t.tablename || '_ver', v_t.objectkeyfield), p_2 => p_revisions) AS r;
    END LOOP;
END
$$;

COMMENT ON FUNCTION tgsis.changed_objects(integer[]) IS
    'per versioned table, the objects (class, key as text) with row versions written or closed in the given revisions, and a fingerprint (md5) of those row versions';

-- ==== versioning/current_conflicts.sql ====
-- tgsis.current_conflicts(versionid): the objects changed both in a version and in its parent since its base, as they stand now.
-- An object conflicts when, since the version's initrevision, it was changed
-- both in the version and in the parent. The marks fingerprint each side's
-- changes, so that a solution recorded for one state can be told from a
-- later one. Computed, not stored: tgsis.find_conflicts stores it.
CREATE FUNCTION tgsis.current_conflicts(p_versionid integer)
RETURNS TABLE (objectclass text, objectkey text, conflicttype text[], childtables text[], parenttables text[],
               childmark text, parentmark text)
LANGUAGE sql
STABLE
AS $$
    WITH version AS (
        SELECT v.versionid, v.parentid, v.initrevision FROM tgsis.versions v WHERE v.versionid = p_versionid),
    parent_revisions AS (
        SELECT coalesce(array_agg(r.revision), '{}') AS revs
          FROM tgsis.revisions r, version v WHERE r.versionid = v.parentid AND r.revision > v.initrevision),
    changes AS (
        SELECT c.side, c.objectclass, c.objectkey, array_agg(c.shortname ORDER BY c.shortname) AS tables,
               md5(string_agg(c.shortname || ':' || c.mark, ',' ORDER BY c.shortname)) AS mark
          FROM (SELECT 'child' AS side, o.* FROM tgsis.changed_objects(tgsis.own_working_revisions(p_versionid)) AS o
                UNION ALL
                SELECT 'parent', o.* FROM parent_revisions p, tgsis.changed_objects(p.revs) AS o) AS c
         GROUP BY 1, 2, 3)
    SELECT c.objectclass, c.objectkey,
           ARRAY(SELECT unnest(c.tables) INTERSECT SELECT unnest(p.tables) ORDER BY 1),
           c.tables, p.tables, c.mark, p.mark
      FROM changes c JOIN changes p USING (objectclass, objectkey)
     WHERE c.side = 'child' AND p.side = 'parent'
$$;

COMMENT ON FUNCTION tgsis.current_conflicts(integer) IS
    'objects of a version changed on both sides since its base, with the tables each side changed and fingerprints of the changes; computed now, not stored (tgsis.find_conflicts stores them)';

-- ==== versioning/find_conflicts.sql ====
-- tgsis.find_conflicts(version): (re)compute the conflicting objects of a version against its parent.
-- An object conflicts when, since the version's initrevision, it was changed
-- both in the version and in the parent (tgsis.current_conflicts). Solutions
-- recorded earlier are kept while neither side changed the object again;
-- conflicts that are gone are removed. Only a role that may write in the
-- version or merge into its parent stores the result (which locks the
-- version's conflict rows until its transaction ends): anyone else who may
-- read gets the same answer computed, without writing or locking anything.
CREATE FUNCTION tgsis.find_conflicts(p_version text)
RETURNS SETOF tgsis.conflicts
LANGUAGE plpgsql
VOLATILE
SECURITY DEFINER
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_version tgsis.versions;
    v_role    name := tgsis.calling_role();
BEGIN
    SELECT * INTO v_version FROM tgsis.versions WHERE versionid = tgsis.version_id(p_version);
    IF v_version.parentid IS NULL THEN
        RAISE EXCEPTION 'version DEFAULT has no parent to conflict with' USING ERRCODE = 'TG100';
    END IF;
    IF NOT (tgsis.holds_version_privilege(v_version.versionid, 'write', v_role)
            OR tgsis.holds_version_privilege(v_version.parentid, 'merge', v_role)) THEN
        RETURN QUERY
            SELECT v_version.versionid, f.objectclass, f.objectkey, f.conflicttype, f.childtables, f.parenttables,
                   f.childmark, f.parentmark,
                   CASE WHEN (k.childmark, k.parentmark) = (f.childmark, f.parentmark) THEN k.solution ELSE 'unsolved' END,
                   coalesce(k.detected_at, now()),
                   CASE WHEN (k.childmark, k.parentmark) = (f.childmark, f.parentmark) THEN k.solved_at END,
                   CASE WHEN (k.childmark, k.parentmark) = (f.childmark, f.parentmark) THEN k.solved_by END
              FROM tgsis.current_conflicts(v_version.versionid) AS f
              LEFT JOIN tgsis.conflicts k ON k.versionid = v_version.versionid AND k.objectclass = f.objectclass
                                         AND k.objectkey = f.objectkey
             ORDER BY f.objectclass, f.objectkey;
        RETURN;
    END IF;

    WITH found AS (SELECT * FROM tgsis.current_conflicts(v_version.versionid)),
    gone AS (
        DELETE FROM tgsis.conflicts k
         WHERE k.versionid = v_version.versionid
           AND NOT EXISTS (SELECT FROM found f WHERE f.objectclass = k.objectclass AND f.objectkey = k.objectkey))
    INSERT INTO tgsis.conflicts AS k (versionid, objectclass, objectkey, conflicttype, childtables, parenttables,
                                      childmark, parentmark)
    SELECT v_version.versionid, f.* FROM found f
        ON CONFLICT (versionid, objectclass, objectkey) DO UPDATE
       SET conflicttype = excluded.conflicttype, childtables = excluded.childtables,
           parenttables = excluded.parenttables, childmark = excluded.childmark, parentmark = excluded.parentmark,
           -- a solution holds for the state it was given on
           solution = CASE WHEN (k.childmark, k.parentmark) = (excluded.childmark, excluded.parentmark)
                           THEN k.solution ELSE 'unsolved' END,
           solved_at = CASE WHEN (k.childmark, k.parentmark) = (excluded.childmark, excluded.parentmark)
                            THEN k.solved_at END,
           solved_by = CASE WHEN (k.childmark, k.parentmark) = (excluded.childmark, excluded.parentmark)
                            THEN k.solved_by END;
    RETURN QUERY SELECT * FROM tgsis.conflicts WHERE versionid = v_version.versionid ORDER BY objectclass, objectkey;
END
$$;

COMMENT ON FUNCTION tgsis.find_conflicts(text) IS
    '(re)compute and return the objects changed both in a version and in its parent since the version was based; keeps solutions while neither side changed the object again; stored only for roles that may write in the version or merge into its parent';

-- ==== versioning/resolve_conflict.sql ====
-- tgsis.resolve_conflict(version, objectclass, objectkey, solution): record how a conflicting object is to be merged.
-- parent: keep the parent's object; child: take the version's; manual: the
-- version already holds the merged object (write it there first). The
-- solution holds for the current state of both sides (find_conflicts sets
-- it back to unsolved when either changes the object again).
CREATE FUNCTION tgsis.resolve_conflict(p_version text, p_objectclass text, p_objectkey text, p_solution text)
RETURNS tgsis.conflicts
LANGUAGE plpgsql
VOLATILE
SECURITY DEFINER
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_id  integer := tgsis.version_id(p_version);
    v_row tgsis.conflicts;
BEGIN
    IF p_solution IS NULL OR lower(p_solution) NOT IN ('parent', 'child', 'manual', 'unsolved') THEN
        RAISE EXCEPTION 'solution % is not parent, child, manual or unsolved', coalesce(quote_literal(p_solution), 'NULL')
            USING ERRCODE = 'TG100';
    END IF;
    PERFORM tgsis.require_version_privilege(v_id, 'write', 'resolve conflicts of');
    -- the marks must be those of now: a manual solution is written just before it is recorded
    PERFORM tgsis.find_conflicts(p_version);
    UPDATE tgsis.conflicts
       SET solution = lower(p_solution),
           solved_at = CASE WHEN lower(p_solution) <> 'unsolved' THEN now() END,
           solved_by = CASE WHEN lower(p_solution) <> 'unsolved' THEN tgsis.calling_role() END
     WHERE versionid = v_id AND objectclass = p_objectclass AND objectkey = p_objectkey
    RETURNING * INTO v_row;
    IF NOT FOUND THEN
        RAISE EXCEPTION 'object % of class % is not in conflict in version %', quote_literal(p_objectkey),
                quote_literal(p_objectclass), quote_literal(p_version)
            USING ERRCODE = 'TG200', HINT = format('SELECT * FROM tgsis.find_conflicts(%L) lists the conflicts', p_version);
    END IF;
    RETURN v_row;
END
$$;

COMMENT ON FUNCTION tgsis.resolve_conflict(text, text, text, text) IS
    'record the solution of a conflicting object: parent (keep the parent''s), child (take the version''s), manual (the version holds the merged object), or unsolved';

-- ==== versioning/conflict_rows.sql ====
-- tgsis.conflict_rows(version, objectclass, objectkey): both sides' rows of a conflicting object, for psql users.
-- side 'child' is what the version sees, 'parent' what the parent sees now;
-- rows equal on both sides are left out.
CREATE FUNCTION tgsis.conflict_rows(p_version text, p_objectclass text, p_objectkey text)
RETURNS TABLE (shortname text, side text, rowkey jsonb, "row" jsonb)
LANGUAGE plpgsql
STABLE
AS $$
DECLARE
    v_version tgsis.versions;
    v_parent  integer[];
    v_t       tgsis.versioned_tables;
BEGIN
    SELECT * INTO v_version FROM tgsis.versions WHERE versionid = tgsis.version_id(p_version);
    PERFORM tgsis.check_object_class(p_objectclass);
    SELECT workingset INTO v_parent FROM tgsis.versions WHERE versionid = v_version.parentid;
    FOR v_t IN SELECT * FROM tgsis.versioned_tables WHERE objectclass = p_objectclass ORDER BY iudorder, shortname LOOP
        RETURN QUERY EXECUTE format(
            'WITH rows AS (
                 SELECT s.side, to_jsonb(v.*) - ''revision'' - ''lastrevs'' - ''revclosed'' AS r, v.revision
                   FROM %I.%I v, (VALUES (''child'', $2), (''parent'', $3)) AS s(side, revs)
                  WHERE v.%I::text = $1 AND v.revision = ANY (s.revs) AND NOT (v.lastrevs && s.revs))
             SELECT %L::text, a.side, (SELECT jsonb_object_agg(key, a.r -> key) FROM unnest($4::text[]) AS key), a.r
               FROM rows a
              WHERE NOT EXISTS (SELECT FROM rows b WHERE b.side <> a.side AND b.r = a.r)
              ORDER BY 3, 2',
            v_t.schemaname, v_t.tablename || '_ver', v_t.objectkeyfield, v_t.shortname)
          USING p_objectkey, v_version.workingset, v_parent, v_t.keycolumns;
    END LOOP;
END
$$;

COMMENT ON FUNCTION tgsis.conflict_rows(text, text, text) IS
    'rows of an object that differ between a version (side child) and its parent (side parent), per table, as jsonb with their row key';

-- ==== versioning/unsolved_conflicts_check.sql ====
-- tgsis.check_no_unsolved_conflicts(version, action): recompute a version's conflicts; TG302 naming the unsolved ones.
CREATE FUNCTION tgsis.check_no_unsolved_conflicts(p_version text, p_action text)
RETURNS void
LANGUAGE plpgsql
VOLATILE
AS $$
DECLARE
    v_count integer;
    v_list  text;
BEGIN
    SELECT count(*), string_agg(format('%s %s (%s)', objectclass, objectkey,
                                       coalesce(nullif(array_to_string(conflicttype, ', '), ''), 'different tables')),
                                '; ' ORDER BY objectclass, objectkey)
      INTO v_count, v_list
      FROM tgsis.find_conflicts(p_version) WHERE solution = 'unsolved';
    IF v_count > 0 THEN
        RAISE EXCEPTION '% of version % refused: % unsolved conflict(s): %', p_action, quote_literal(p_version), v_count, v_list
            USING ERRCODE = 'TG302',
                  HINT = format('record a solution for each: SELECT tgsis.resolve_conflict(%L, class, key, ''parent''|''child''|''manual'')',
                                p_version);
    END IF;
END
$$;

COMMENT ON FUNCTION tgsis.check_no_unsolved_conflicts(text, text) IS
    'recompute the conflicts of a version and raise TG302 naming the unsolved ones (before a merge or refresh)';

-- ==== versioning/lock_for_merge.sql ====
-- tgsis.lock_for_merge(version, action): lock a version and its parent for a merge or refresh; returns the version's row.
-- Parent first, then child: the order every merge and refresh takes. It waits
-- for writers of either (write_revision share-locks a version) and for another
-- merge or refresh of either. Then the conflicts are recomputed: TG302 names
-- the unsolved ones.
CREATE FUNCTION tgsis.lock_for_merge(p_version text, p_action text)
RETURNS tgsis.versions
LANGUAGE plpgsql
VOLATILE
AS $$
DECLARE
    v_child tgsis.versions;
BEGIN
    PERFORM tgsis.require_read_committed(p_action);
    SELECT * INTO v_child FROM tgsis.versions WHERE versionid = tgsis.version_id(p_version);
    IF v_child.parentid IS NULL THEN
        RAISE EXCEPTION 'version DEFAULT has no parent: nothing to %', p_action USING ERRCODE = 'TG100';
    END IF;
    PERFORM FROM tgsis.versions WHERE versionid = v_child.parentid FOR UPDATE;
    SELECT * INTO v_child FROM tgsis.versions WHERE versionid = v_child.versionid FOR UPDATE;
    IF NOT FOUND THEN
        -- a merge with remove (or delete_version) committed while this one waited: go
        -- no further with an empty row (a version re-created under the same name
        -- meanwhile is another version, and not the one asked for)
        RAISE EXCEPTION 'version % does not exist', quote_literal(p_version)
            USING ERRCODE = 'TG200', DETAIL = format('It was removed while this %s waited for it.', p_action);
    END IF;
    PERFORM tgsis.check_no_unsolved_conflicts(p_version, p_action);
    RETURN v_child;
END
$$;

COMMENT ON FUNCTION tgsis.lock_for_merge(text, text) IS
    'lock a version and its parent (parent first) for a merge or refresh, then refuse (TG302) while conflicts are unsolved; returns the version''s row';

-- ==== versioning/copy_object_state.sql ====
-- tgsis.copy_object_state(objectclass, keys, from_set, to_set, revision): make objects look in to_set as they look in from_set.
-- For every table of the class, the rows of the objects visible in to_set but
-- not in from_set are closed with revision (deleted when written in it), and
-- the rows visible in from_set but not in to_set are copied with revision.
-- Rows visible in both are left alone: unchanged rows are never copied.
-- The common step of merge (child's state into the parent) and refresh.
-- Returns the rows written (closed, deleted and copied).
CREATE FUNCTION tgsis.copy_object_state(
    p_objectclass text,
    p_keys        text[],
    p_from        integer[],
    p_to          integer[],
    p_revision    integer)
RETURNS bigint
LANGUAGE plpgsql
VOLATILE
AS $$
DECLARE
    v_t       tgsis.versioned_tables;
    v_ver     text;
    v_cols    text;
    v_keytype text;
    v_count   bigint;
    v_written bigint := 0;
BEGIN
    IF cardinality(p_keys) = 0 THEN
        RETURN 0;
    END IF;
    -- closes first (reverse iudorder), then copies (iudorder): closing touches
    -- only rows p_from does not see, so it cannot change what is copied, and
    -- copies made first would look like rows to close
    FOR v_t IN SELECT * FROM tgsis.versioned_tables WHERE objectclass = p_objectclass ORDER BY iudorder DESC, shortname LOOP
        v_ver := format('%I.%I', v_t.schemaname, v_t.tablename || '_ver');
        -- keys compared in the column's own type, so that its index serves
        SELECT format_type(atttypid, atttypmod) INTO v_keytype FROM pg_catalog.pg_attribute
         WHERE attrelid = v_ver::regclass AND attname = v_t.objectkeyfield;
        -- (every statement on storage as its owner: tgsis.storage_run)
        SELECT r[1]::bigint INTO v_count FROM tgsis.storage_run(v_t, true, format(
            'DELETE FROM %s v WHERE v.%I = ANY ($1::%s[]) AND v.revision = $4
                AND v.revision = ANY ($3) AND NOT (v.lastrevs && $3)
                AND NOT (v.revision = ANY ($2) AND NOT (v.lastrevs && $2))',
            v_ver, v_t.objectkeyfield, v_keytype), p_keys, p_from, p_to, p_revision) AS r;
        v_written := v_written + v_count;
        -- other versions see these rows too (the siblings of a merged version share
        -- the parent's rows): closed without waiting for one while holding others
        v_count := tgsis.update_shared_rows(v_t, 'lastrevs = v.lastrevs || $4', format(
            'v.%I = ANY ($1::%s[]) AND v.revision <> $4
                AND v.revision = ANY ($3) AND NOT (v.lastrevs && $3)
                AND NOT (v.revision = ANY ($2) AND NOT (v.lastrevs && $2))',
            v_t.objectkeyfield, v_keytype), p_keys, p_from, p_to, p_revision);
        v_written := v_written + v_count;
    END LOOP;
    FOR v_t IN SELECT * FROM tgsis.versioned_tables WHERE objectclass = p_objectclass ORDER BY iudorder, shortname LOOP
        v_ver := format('%I.%I', v_t.schemaname, v_t.tablename || '_ver');
        -- every stored column but the generated ones; a fresh revision, nothing closed
        SELECT string_agg(format('%I', attname), ', ' ORDER BY attnum) INTO v_cols
          FROM pg_catalog.pg_attribute
         WHERE attrelid = v_ver::regclass AND attnum > 0 AND NOT attisdropped AND attgenerated = ''
           AND attname NOT IN ('revision', 'lastrevs');
        SELECT format_type(atttypid, atttypmod) INTO v_keytype FROM pg_catalog.pg_attribute
         WHERE attrelid = v_ver::regclass AND attname = v_t.objectkeyfield;
        SELECT r[1]::bigint INTO v_count FROM tgsis.storage_run(v_t, true, format(
            'INSERT INTO %s (%s, revision)
             SELECT %s, $4 FROM %s v
              WHERE v.%I = ANY ($1::%s[])
                AND v.revision = ANY ($2) AND NOT (v.lastrevs && $2)
                AND NOT (v.revision = ANY ($3) AND NOT (v.lastrevs && $3))',
            v_ver, v_cols, v_cols, v_ver, v_t.objectkeyfield, v_keytype), p_keys, p_from, p_to, p_revision) AS r;
        v_written := v_written + v_count;
    END LOOP;
    RETURN v_written;
END
$$;

COMMENT ON FUNCTION tgsis.copy_object_state(text, text[], integer[], integer[], integer) IS
    'make objects of a class look in revision set p_to (plus p_revision) as they look in p_from: close or delete rows only p_to sees, copy rows only p_from sees; returns rows written';

-- ==== versioning/merge_version.sql ====
-- tgsis.merge_version(version, remove): apply a version's changes to its parent's working revision; returns the rows written.
-- One transaction: for every object the version changed (except conflicts
-- solved 'parent') the parent is made to see the version's state, rows the
-- version did not change are not touched. The parent's working revision is
-- then frozen and a new one started. Without p_remove the version goes on
-- from the merged state (its base moves to that revision); with it, the
-- version is deleted. Refused (TG302) while a conflict is unsolved.
CREATE FUNCTION tgsis.merge_version(p_version text, p_remove boolean DEFAULT false)
RETURNS bigint
LANGUAGE plpgsql
VOLATILE
SECURITY DEFINER
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_child   tgsis.versions;
    v_parent  tgsis.versions;
    v_own     integer[];
    v_class   record;
    v_written bigint := 0;
BEGIN
    -- the right to merge into the parent, and to change (or delete) the version itself, whose base moves
    PERFORM tgsis.require_version_privilege(parentid, 'merge', 'merge into'),
            tgsis.require_version_privilege(versionid, CASE WHEN p_remove THEN 'delete' ELSE 'write' END,
                                            CASE WHEN p_remove THEN 'delete' ELSE 'write in' END)
       FROM tgsis.versions WHERE versionid = tgsis.version_id(p_version) AND parentid IS NOT NULL;
    IF coalesce(p_remove, false) AND EXISTS (SELECT FROM tgsis.versions WHERE parentid = tgsis.version_id(p_version)) THEN
        RAISE EXCEPTION 'version % has child versions and cannot be removed by the merge', quote_literal(p_version)
            USING ERRCODE = 'TG202', HINT = 'merge without removing it, or merge or delete its children first';
    END IF;
    v_child := tgsis.lock_for_merge(p_version, 'merge');
    SELECT * INTO v_parent FROM tgsis.versions WHERE versionid = v_child.parentid;

    v_own := tgsis.own_working_revisions(v_child.versionid);
    FOR v_class IN
        SELECT c.objectclass, array_agg(DISTINCT c.objectkey) AS keys
          FROM tgsis.changed_objects(v_own) AS c
         WHERE NOT EXISTS (SELECT FROM tgsis.conflicts k
                            WHERE k.versionid = v_child.versionid AND k.objectclass = c.objectclass
                              AND k.objectkey = c.objectkey AND k.solution = 'parent')
         GROUP BY c.objectclass
    LOOP
        -- an object another version locked stays as it is in the parent too
        PERFORM tgsis.check_objects_unlocked(v_class.objectclass, v_class.keys, v_child.versionid, false);
        v_written := v_written + tgsis.copy_object_state(v_class.objectclass, v_class.keys, v_child.workingset,
                                                         v_parent.workingset, v_parent.workingrevision);
    END LOOP;

    -- the parent's working revision now holds the merge: freeze it, start the next
    PERFORM tgsis.next_working_revision(v_parent.versionid);

    IF coalesce(p_remove, false) THEN
        PERFORM tgsis.delete_version(p_version);
    ELSE
        -- the version goes on from the merged state: everything it had is in the parent now
        PERFORM tgsis.next_working_revision(v_child.versionid, v_parent.workingset, v_parent.workingrevision);
        DELETE FROM tgsis.conflicts WHERE versionid = v_child.versionid;
    END IF;
    RETURN v_written;
END
$$;

COMMENT ON FUNCTION tgsis.merge_version(text, boolean) IS
    'apply a version''s changes (object by object, unchanged rows untouched) to its parent''s working revision in one transaction; refused while conflicts are unsolved; the version goes on from the merged state, or is removed; returns the rows written';

-- ==== versioning/refresh_version.sql ====
-- tgsis.refresh_version(version): bring the parent's changes since the version's base into it; returns the rows written.
-- The version's base moves to the parent's working revision (which is then
-- frozen): objects only the parent changed now look as in the parent, objects
-- only the version changed keep the version's state, and each conflicting
-- object follows its solution ('parent' takes the parent's object, 'child'
-- and 'manual' keep the version's). Refused (TG302) while a conflict is
-- unsolved.
CREATE FUNCTION tgsis.refresh_version(p_version text)
RETURNS bigint
LANGUAGE plpgsql
VOLATILE
SECURITY DEFINER
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_child   tgsis.versions;
    v_parent  tgsis.versions;
    v_own     integer[];
    v_newset  integer[];
    v_next    integer;
    v_class   record;
    v_written bigint := 0;
BEGIN
    PERFORM tgsis.require_version_privilege(tgsis.version_id(p_version), 'write', 'refresh');
    v_child := tgsis.lock_for_merge(p_version, 'refresh');
    SELECT * INTO v_parent FROM tgsis.versions WHERE versionid = v_child.parentid;

    -- the parent's working revision becomes the new base; the version sees
    -- the parent's set up to it, its own revisions, and a new working one
    PERFORM tgsis.next_working_revision(v_parent.versionid);
    v_own := tgsis.own_working_revisions(v_child.versionid);
    v_next := tgsis.next_working_revision(v_child.versionid,
                                          ARRAY(SELECT DISTINCT r FROM unnest(v_parent.workingset || v_own) AS r ORDER BY r),
                                          v_parent.workingrevision);
    SELECT workingset INTO v_newset FROM tgsis.versions WHERE versionid = v_child.versionid;

    -- objects changed on both sides would now show both sides' rows: give each the state its solution says
    FOR v_class IN
        SELECT objectclass, solution = 'parent' AS take_parent, array_agg(objectkey) AS keys
          FROM tgsis.conflicts WHERE versionid = v_child.versionid
         GROUP BY 1, 2
    LOOP
        v_written := v_written + tgsis.copy_object_state(
            v_class.objectclass, v_class.keys,
            CASE WHEN v_class.take_parent THEN v_parent.workingset ELSE v_child.workingset END,
            v_newset, v_next);
    END LOOP;
    DELETE FROM tgsis.conflicts WHERE versionid = v_child.versionid;
    RETURN v_written;
END
$$;

COMMENT ON FUNCTION tgsis.refresh_version(text) IS
    'bring the parent''s changes since the version''s base into the version (its base moves to the parent''s working revision); conflicting objects follow their solutions; refused while conflicts are unsolved; returns the rows written';

-- ==== versioning/diff_versions.sql ====
-- tgsis.diff_versions(a, b, a_revision, b_revision): objects whose rows differ between two versions (or revisions).
-- Per table and object: rows added (seen in b only), removed (in a only) and
-- changed (same row key, other values). Rows both sides see as the same row
-- version are skipped without reading them twice; rows that are different
-- row versions with equal values (e.g. copied by a merge) are not differences.
CREATE FUNCTION tgsis.diff_versions(
    p_a          text,
    p_b          text,
    p_a_revision integer DEFAULT NULL,
    p_b_revision integer DEFAULT NULL)
RETURNS TABLE (objectclass text, objectkey text, shortname text, added bigint, removed bigint, changed bigint)
LANGUAGE plpgsql
STABLE
AS $$
DECLARE
    v_a    integer[] := tgsis.revision_set(tgsis.version_id(p_a), p_a_revision);
    v_b    integer[] := tgsis.revision_set(tgsis.version_id(p_b), p_b_revision);
    v_t    tgsis.versioned_tables;
    v_keys text;
BEGIN
    FOR v_t IN SELECT * FROM tgsis.versioned_tables ORDER BY objectclass, iudorder, shortname LOOP
        SELECT string_agg(format('%I', k), ', ' ORDER BY o) INTO v_keys FROM unnest(v_t.keycolumns) WITH ORDINALITY AS u(k, o);
        RETURN QUERY EXECUTE format(
            'WITH a AS (SELECT %1$s, v.%2$I::text AS obj, to_jsonb(v.*) - ''revision'' - ''lastrevs'' - ''revclosed'' AS r
                          FROM %3$I.%4$I v
                         WHERE v.revision = ANY ($1) AND NOT (v.lastrevs && $1)
                           AND NOT (v.revision = ANY ($2) AND NOT (v.lastrevs && $2))),
                  b AS (SELECT %1$s, v.%2$I::text AS obj, to_jsonb(v.*) - ''revision'' - ''lastrevs'' - ''revclosed'' AS r
                          FROM %3$I.%4$I v
                         WHERE v.revision = ANY ($2) AND NOT (v.lastrevs && $2)
                           AND NOT (v.revision = ANY ($1) AND NOT (v.lastrevs && $1)))
             SELECT %5$L::text, coalesce(a.obj, b.obj), %6$L::text,
                    count(*) FILTER (WHERE a.r IS NULL), count(*) FILTER (WHERE b.r IS NULL),
                    count(*) FILTER (WHERE a.r IS NOT NULL AND b.r IS NOT NULL)
               FROM a FULL JOIN b USING (%1$s)
              WHERE a.r IS DISTINCT FROM b.r
              GROUP BY 2 ORDER BY 2',
            v_keys, v_t.objectkeyfield, v_t.schemaname, v_t.tablename || '_ver', v_t.objectclass, v_t.shortname)
          USING v_a, v_b;
    END LOOP;
END
$$;

COMMENT ON FUNCTION tgsis.diff_versions(text, text, integer, integer) IS
    'objects whose rows differ from version a (at a revision) to version b: per table, rows added, removed and changed (by row key and values)';

-- ==== versioning/compress_versions.sql ====
-- tgsis.compress_versions(dry_run): remove the revisions, and the row versions, no version, named revision or child can reach any more; returns what it removed.
-- Kept revisions: every version's working revision, every named revision,
-- every version's base (initrevision), and what the next merge or
-- find_conflicts of a version reads: its own working revisions and its
-- parent's revisions since its base. Each kept revision, and each working
-- set, goes on seeing exactly what it saw. Then:
--   rows:        row versions that no kept set sees go, except those closed
--                in a revision a conflict check reads (tgsis.conflicts
--                fingerprints them: a solution must not fall back to unsolved);
--   lastrevs:    entries in no kept set go (no set that exists or can be made
--                from them holds them: they hide nothing), again except in
--                rows a conflict check reads;
--   revisions:   the others go (goto_revision refuses them with TG200);
--   set entries: their numbers go from the kept sets once no row version
--                mentions them (numbers still on rows stay, as plain labels;
--                0 always stays).
-- One transaction: every version row is locked (writers, merges and new
-- revisions wait), the _ver tables are locked against writes. p_dry_run
-- reports the same figures and changes nothing (it blocks no writer).
-- Returns one row per (what, name) with something removed: what is 'rows'
-- or 'lastrevs' (name: schema.table), 'revisions' or 'set entries' (name:
-- the version).
CREATE FUNCTION tgsis.compress_versions(p_dry_run boolean DEFAULT false)
RETURNS TABLE (what text, name text, removed bigint)
LANGUAGE plpgsql
VOLATILE
SECURITY DEFINER
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_dry     boolean := coalesce(p_dry_run, false);
    v_checked integer[];  -- revisions whose changes merge and find_conflicts read
    v_keep    integer[];  -- revisions kept
    v_sets    text[];     -- the revision sets that stay viewable (integer[] as text)
    v_seen    integer[];  -- every revision in one of them
    v_loose   integer[];  -- numbers in kept sets that are not kept revisions
    v_unused  integer[];  -- those that no row version mentions any more
    v_used    integer[];
    v_found   integer[];
    v_t       tgsis.versioned_tables;
    v_ver     text;
    -- a row version stays when a kept set sees it, or when it was closed in a
    -- revision a conflict check reads ($1 sets, $2 their revisions, $3 v_checked)
    v_with    CONSTANT text := 'WITH sets AS MATERIALIZED (SELECT s::integer[] AS revs FROM unnest($1::text[]) AS u(s)) ';
    v_kept    CONSTANT text := '(v.lastrevs && $3 OR (v.revision = ANY ($2) AND (NOT v.revclosed OR EXISTS (
                                   SELECT FROM sets WHERE v.revision = ANY (sets.revs) AND NOT (v.lastrevs && sets.revs)))))';
    v_trim    CONSTANT text := 'NOT (v.lastrevs <@ $2) AND NOT (v.lastrevs && $3)';
BEGIN
    -- writers share-lock their version (tgsis.write_revision); merge, refresh,
    -- create_version, save_revision and delete_version lock it for update
    IF v_dry THEN
        PERFORM FROM tgsis.versions v ORDER BY v.versionid FOR SHARE;
    ELSE
        PERFORM FROM tgsis.versions v ORDER BY v.versionid FOR UPDATE;
    END IF;
    LOCK TABLE tgsis.versioned_tables IN SHARE MODE;  -- no table is versioned or unversioned meanwhile

    SELECT coalesce(array_agg(DISTINCT c.r ORDER BY c.r), '{}') INTO v_checked FROM (
        SELECT unnest(tgsis.own_working_revisions(v.versionid)) FROM tgsis.versions v WHERE v.parentid IS NOT NULL
        UNION ALL
        SELECT r.revision FROM tgsis.versions v JOIN tgsis.revisions r ON r.versionid = v.parentid
         WHERE r.revision > v.initrevision) AS c(r);
    SELECT array_agg(DISTINCT k.r ORDER BY k.r) INTO v_keep FROM (
        SELECT v.workingrevision FROM tgsis.versions v
        UNION ALL
        SELECT v.initrevision FROM tgsis.versions v WHERE v.initrevision IS NOT NULL
        UNION ALL
        SELECT r.revision FROM tgsis.revisions r WHERE r.name IS NOT NULL
        UNION ALL
        SELECT unnest(v_checked)) AS k(r);
    SELECT array_agg(DISTINCT s.revs::text) INTO v_sets FROM (
        SELECT v.workingset FROM tgsis.versions v
        UNION ALL
        SELECT r.visibleset FROM tgsis.revisions r WHERE r.revision = ANY (v_keep) AND r.visibleset IS NOT NULL) AS s(revs);
    v_seen := ARRAY(SELECT DISTINCT u.r FROM unnest(v_sets) AS s(revs), unnest(s.revs::integer[]) AS u(r) ORDER BY 1);
    -- 0 stays in every set whatever happens to its revision: enable_versioning labels a table's existing rows with it
    v_loose := ARRAY(SELECT u.r FROM unnest(v_seen) AS u(r) WHERE u.r <> ALL (v_keep) AND u.r <> 0 ORDER BY 1);
    v_used := '{}';

    FOR v_t IN SELECT * FROM tgsis.versioned_tables t ORDER BY t.schemaname, t.tablename LOOP
        v_ver := format('%I.%I', v_t.schemaname, v_t.tablename || '_ver');
        name := format('%s.%s', v_t.schemaname, v_t.tablename);
        -- every statement on storage as its owner (tgsis.storage_run): $1 the kept sets, $2 their
        -- revisions, $3 the checked revisions, $5 the loose numbers
        IF NOT v_dry THEN
            EXECUTE format('LOCK TABLE %s IN EXCLUSIVE MODE', v_ver);  -- reads go on, writes wait (runs no code of the table's)
        END IF;

        what := 'rows';
        IF v_dry THEN
            SELECT r[1]::bigint INTO removed FROM tgsis.storage_run(v_t, false,
                v_with || format('SELECT ARRAY[count(*)::text] FROM %s v WHERE NOT %s', v_ver, v_kept),
                v_sets, v_seen, v_checked) AS r;
        ELSE
            SELECT r[1]::bigint INTO removed FROM tgsis.storage_run(v_t, true,
                v_with || format('DELETE FROM %s v WHERE NOT %s', v_ver, v_kept), v_sets, v_seen, v_checked) AS r;
        END IF;
        IF removed > 0 THEN
            RETURN NEXT;
        END IF;

        what := 'lastrevs';
        SELECT r[1]::bigint INTO removed FROM tgsis.storage_run(v_t, false, v_with || format(
            'SELECT ARRAY[coalesce(sum((SELECT count(*) FROM unnest(v.lastrevs) AS l(r) WHERE l.r <> ALL ($2))), 0)::text]
               FROM %s v WHERE %s AND %s', v_ver, v_trim, v_kept), v_sets, v_seen, v_checked) AS r;
        IF NOT v_dry AND removed > 0 THEN
            PERFORM FROM tgsis.storage_run(v_t, true, format(
                'UPDATE %s v SET lastrevs = ARRAY(SELECT l.r FROM unnest(v.lastrevs) WITH ORDINALITY AS l(r, o)
                                                  WHERE l.r = ANY ($2) ORDER BY l.o)
                  WHERE %s', v_ver, v_trim), v_sets, v_seen, v_checked);
        END IF;
        IF removed > 0 THEN
            RETURN NEXT;
        END IF;

        -- loose numbers still on a (remaining) row version stay in the sets
        IF cardinality(v_loose) > 0 THEN
            SELECT r::integer[] INTO v_found FROM tgsis.storage_run(v_t, false, v_with || format(
                'SELECT coalesce(array_agg(DISTINCT u.r::text), ''{}'') FROM %s v, unnest(v.revision || v.lastrevs) AS u(r)
                  WHERE u.r = ANY ($5) AND %s', v_ver, v_kept), v_sets, v_seen, v_checked, NULL, v_loose::bigint[]) AS r;
            v_used := v_used || v_found;
        END IF;
    END LOOP;
    v_unused := ARRAY(SELECT u.r FROM unnest(v_loose) AS u(r) WHERE u.r <> ALL (v_used) ORDER BY 1);

    RETURN QUERY
        SELECT 'revisions', v.name, count(*)
          FROM tgsis.versions v JOIN tgsis.revisions r ON r.versionid = v.versionid
         WHERE r.revision <> ALL (v_keep)
         GROUP BY v.versionid, v.name ORDER BY v.versionid;
    RETURN QUERY
        SELECT 'set entries', v.name, n.removed
          FROM tgsis.versions v,
               LATERAL (SELECT (SELECT count(*) FROM unnest(v.workingset) AS w(r) WHERE w.r = ANY (v_unused))
                             + (SELECT count(*) FROM tgsis.revisions k, unnest(k.visibleset) AS s(r)
                                 WHERE k.versionid = v.versionid AND k.revision = ANY (v_keep) AND s.r = ANY (v_unused))
                          AS removed) AS n
         WHERE n.removed > 0
         ORDER BY v.versionid;
    IF v_dry THEN
        RETURN;
    END IF;

    DELETE FROM tgsis.revisions r WHERE r.revision <> ALL (v_keep);
    IF cardinality(v_unused) > 0 THEN
        UPDATE tgsis.versions v
           SET workingset = ARRAY(SELECT u.r FROM unnest(v.workingset) WITH ORDINALITY AS u(r, o)
                                   WHERE u.r <> ALL (v_unused) ORDER BY u.o)
         WHERE v.workingset && v_unused;
        UPDATE tgsis.revisions r
           SET visibleset = ARRAY(SELECT u.r FROM unnest(r.visibleset) WITH ORDINALITY AS u(r, o)
                                   WHERE u.r <> ALL (v_unused) ORDER BY u.o)
         WHERE r.visibleset && v_unused;
    END IF;
END
$$;

REVOKE ALL ON FUNCTION tgsis.compress_versions(boolean) FROM PUBLIC;

COMMENT ON FUNCTION tgsis.compress_versions(boolean) IS
    'remove the revisions no version, named revision or child can reach (kept: working, named, bases, and what merges and conflict checks read), the row versions only they saw and lastrevs entries that hide nothing; never changes what a version or kept revision sees, nor conflicts; p_dry_run only reports; rows (what, name, removed)';

-- ==== versioning/storage_table.sql ====
-- tgsis.storage_table(schema, table): where a table's rows are physically stored: <table>_ver when versioned, else the table.
CREATE FUNCTION tgsis.storage_table(p_schema text, p_table text)
RETURNS text
LANGUAGE sql
STABLE
PARALLEL SAFE
AS $$
    SELECT format('%I.%I', p_schema,
                  CASE WHEN EXISTS (SELECT FROM tgsis.versioned_tables t WHERE t.schemaname = p_schema AND t.tablename = p_table)
                       THEN p_table || '_ver' ELSE p_table END)
$$;

COMMENT ON FUNCTION tgsis.storage_table(text, text) IS
    'quoted schema.name of the relation that stores a table''s rows: <table>_ver when the table is versioned, else the table itself';

-- ==== versioning/close_object_rows.sql ====
-- tgsis.close_object_rows(schema, table, keyfield, keys, idfield, ids): the versioned half of tgsis.delete_object_rows.
-- SECURITY DEFINER: roles other than storage's owner may not update or
-- delete rows of <table>_ver (they could rewrite other versions), so the
-- set-based delete of the client runs here, for the calling role, after the
-- checks a write through the view makes: the table is one tgsis versions
-- (tgsis.versioned_tables, which only tgsis writes), the role may DELETE
-- from its view, holds the write right on its session's version
-- (tgsis.write_revision) and no other version locked the objects. The
-- objects' write locks are taken exclusively first: no write through the
-- view is in flight on them (it would re-create a closed row), later ones
-- find them changed. Rows written in the working revision go, older visible
-- rows get the working revision appended to lastrevs. Returns rows affected.
CREATE FUNCTION tgsis.close_object_rows(p_schema text, p_table text, p_keyfield text, p_keys bigint[],
                                        p_idfield text DEFAULT NULL, p_ids bigint[] DEFAULT NULL)
RETURNS bigint
LANGUAGE plpgsql
VOLATILE
SECURITY DEFINER
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_t       tgsis.versioned_tables;
    v_write   record;
    v_deleted bigint;
    v_closed  bigint;
    v_where   text;
BEGIN
    PERFORM tgsis.require_read_committed('a set-based delete of versioned objects');
    SELECT * INTO v_t FROM tgsis.versioned_tables WHERE schemaname = p_schema AND tablename = p_table;
    IF NOT FOUND THEN
        RAISE EXCEPTION 'table %.% is not versioned', quote_ident(p_schema), quote_ident(p_table)
            USING ERRCODE = 'TG200', HINT = 'SELECT * FROM tgsis.versioned_tables lists the versioned tables';
    END IF;
    IF p_keyfield IS DISTINCT FROM v_t.objectkeyfield THEN
        RAISE EXCEPTION 'the object key of %.% is %, not %', quote_ident(p_schema), quote_ident(p_table),
                quote_ident(v_t.objectkeyfield), coalesce(quote_ident(p_keyfield), 'NULL')
            USING ERRCODE = 'TG100';
    END IF;
    IF p_idfield IS NOT NULL AND NOT EXISTS (
            SELECT FROM pg_attribute WHERE attrelid = format('%I.%I', p_schema, p_table)::regclass
                                        AND attname = p_idfield AND attnum > 0 AND NOT attisdropped) THEN
        RAISE EXCEPTION 'table %.% has no column %', quote_ident(p_schema), quote_ident(p_table), quote_ident(p_idfield)
            USING ERRCODE = 'TG100';
    END IF;
    IF NOT has_table_privilege(tgsis.calling_role(), format('%I.%I', p_schema, p_table)::regclass, 'DELETE') THEN
        RAISE EXCEPTION 'role % may not delete from %.%', quote_ident(tgsis.calling_role()), quote_ident(p_schema),
                quote_ident(p_table)
            USING ERRCODE = 'TG002', HINT = 'its owner can GRANT DELETE on it';
    END IF;
    SELECT * INTO v_write FROM tgsis.write_revision();
    PERFORM tgsis.check_objects_unlocked(v_t.objectclass, p_keys::text[]);
    PERFORM tgsis.object_write_lock(v_t.objectclass, p_keys::text[]);
    -- as the storage's owner (tgsis.storage_run): $1 keys, $3 the working set, $4 the working revision, $5 ids
    v_where := format('%I = ANY ($1::bigint[])', p_keyfield)
               || CASE WHEN p_idfield IS NOT NULL THEN format(' AND %I = ANY ($5)', p_idfield) ELSE '' END;
    SELECT r[1]::bigint INTO v_deleted FROM tgsis.storage_run(v_t, true, format(
        'DELETE FROM %I.%I WHERE %s AND revision = $4', p_schema, p_table || '_ver', v_where),
        p_keys::text[], NULL, v_write.revisions, v_write.revision, p_ids) AS r;
    SELECT r[1]::bigint INTO v_closed FROM tgsis.storage_run(v_t, true, format(
        'UPDATE %I.%I v SET lastrevs = v.lastrevs || $4
          WHERE %s AND (v.revision = ANY ($3)) IS TRUE AND NOT (v.lastrevs && $3)', p_schema, p_table || '_ver', v_where),
        p_keys::text[], NULL, v_write.revisions, v_write.revision, p_ids) AS r;
    RETURN v_deleted + v_closed;
END
$$;

COMMENT ON FUNCTION tgsis.close_object_rows(text, text, text, bigint[], text, bigint[]) IS
    'set-based delete of objects'' rows (some of them with idfield/ids) from a versioned table in the session''s version, for roles that may not write its storage: checks DELETE on the view, the write right, object locks; takes the objects'' write locks; returns rows affected';

-- ==== versioning/delete_object_rows.sql ====
-- tgsis.delete_object_rows(schema, table, keyfield, keys, idfield, ids): delete objects' rows (or some of them) in the session's version, set-based.
-- A plain table's rows are deleted with the caller's rights. On a versioned
-- table this is what the INSTEAD OF trigger does row by row, in two
-- statements (tgsis.close_object_rows, with tgsis's rights after the same
-- checks): rows written in the working revision go, older visible rows get
-- the working revision appended to lastrevs, and objects locked by another
-- version are refused (TG303). With p_idfield and p_ids only the
-- rows whose id is one of p_ids go: the removed vertices, simplices or
-- property rows of an edited mesh (tgsis.save_feature). Returns rows affected.
CREATE FUNCTION tgsis.delete_object_rows(p_schema text, p_table text, p_keyfield text, p_keys bigint[],
                                         p_idfield text DEFAULT NULL, p_ids bigint[] DEFAULT NULL)
RETURNS bigint
LANGUAGE plpgsql
VOLATILE
AS $$
DECLARE
    v_deleted bigint;
    v_where   text;
BEGIN
    IF to_regclass(format('%I.%I', p_schema, p_table)) IS NULL THEN
        RAISE EXCEPTION 'table %.% does not exist', quote_ident(p_schema), quote_ident(p_table)
            USING ERRCODE = 'TG200';
    END IF;
    IF (p_idfield IS NULL) <> (p_ids IS NULL) THEN
        RAISE EXCEPTION 'delete_object_rows takes an id column and ids together, or neither'
            USING ERRCODE = 'TG100', DETAIL = format('idfield %s, ids %s', coalesce(p_idfield, 'NULL'),
                                                      coalesce(p_ids::text, 'NULL'));
    END IF;
    IF p_ids IS NOT NULL AND cardinality(p_ids) = 0 THEN
        RETURN 0;
    END IF;
    v_where := format('%I = ANY ($1)', p_keyfield)
               || CASE WHEN p_idfield IS NOT NULL THEN format(' AND %I = ANY ($4)', p_idfield) ELSE '' END;
    IF NOT EXISTS (SELECT FROM tgsis.versioned_tables WHERE schemaname = p_schema AND tablename = p_table) THEN
        EXECUTE format('DELETE FROM %I.%I WHERE %s', p_schema, p_table, v_where)
          USING p_keys, NULL::integer, NULL::integer[], p_ids;
        GET DIAGNOSTICS v_deleted = ROW_COUNT;
        RETURN v_deleted;
    END IF;
    RETURN tgsis.close_object_rows(p_schema, p_table, p_keyfield, p_keys, p_idfield, p_ids);
END
$$;

COMMENT ON FUNCTION tgsis.delete_object_rows(text, text, text, bigint[], text, bigint[]) IS
    'delete the rows of objects (keyfield = any of keys; with idfield and ids only those rows) from a table in the session''s version: plain DELETE, or on a versioned table the set-based equivalent of its trigger (TG303 when another version locked an object); returns rows affected';

-- ==== core/property_types.sql ====
-- The column types a feature class may give its properties: no arbitrary SQL
-- can come in through a type name. Vertex and cell properties must be
-- fixed-width numbers (they travel through binary COPY as numpy arrays).
CREATE TABLE tgsis.property_types (
    typename text    PRIMARY KEY,
    aliases  text[]  NOT NULL DEFAULT '{}',
    per_cell boolean NOT NULL
);

COMMENT ON TABLE tgsis.property_types IS 'types allowed for feature-class properties, with accepted spellings';
COMMENT ON COLUMN tgsis.property_types.typename IS 'canonical type name, as format_type() prints it';
COMMENT ON COLUMN tgsis.property_types.aliases IS 'other accepted spellings (lower case)';
COMMENT ON COLUMN tgsis.property_types.per_cell IS 'allowed for vertex/cell properties (fixed-width numbers), not only per feature';

INSERT INTO tgsis.property_types (typename, aliases, per_cell) VALUES
    ('smallint',                 '{int2}',                         true),
    ('integer',                  '{int,int4}',                     true),
    ('bigint',                   '{int8}',                         true),
    ('real',                     '{float4}',                       true),
    ('double precision',         '{float8,float,double}',          true),
    ('boolean',                  '{bool}',                         true),
    ('numeric',                  '{decimal}',                      false),
    ('text',                     '{varchar,string}',               false),
    ('date',                     '{}',                             false),
    ('timestamp with time zone', '{timestamptz}',                  false),
    ('jsonb',                    '{json}',                         false);

-- ==== core/catalog_row.sql ====
-- tgsis.catalog_row(class): the catalog row of a feature class, or TG200 naming it.
CREATE FUNCTION tgsis.catalog_row(p_class text)
RETURNS tgsis.catalog
LANGUAGE plpgsql
STABLE
AS $$
DECLARE
    v_class tgsis.catalog;
BEGIN
    SELECT * INTO v_class FROM tgsis.catalog WHERE classname = p_class;
    IF NOT FOUND THEN
        RAISE EXCEPTION 'feature class % does not exist', coalesce(quote_literal(p_class), 'NULL')
            USING ERRCODE = 'TG200', HINT = 'SELECT classname FROM tgsis.catalog lists the classes';
    END IF;
    RETURN v_class;
END
$$;

COMMENT ON FUNCTION tgsis.catalog_row(text) IS 'the tgsis.catalog row of a feature class; raises TG200 when there is none';

-- ==== core/property_columns.sql ====
-- tgsis.property_columns(properties, per_cell, what): validated (name, type, size) of a property list.
-- Accepts {"name": "type", ...} or [["name", "type"], ...] or [{"name": ..., "type": ...}, ...];
-- a vertex or cell property may be a vector of k components: ["name", "type", k] or
-- {"name": ..., "type": ..., "size": k} (a file's ESIZES k property: one column, an array of k values);
-- a vertex or cell property may name its own alignment, {"name": ..., "type": ..., "alignment": "CELL"}
-- (alignment is per property: NULL here means the class's).
CREATE FUNCTION tgsis.property_columns(p_properties jsonb, p_per_cell boolean, p_what text)
RETURNS TABLE (name text, typename text, ord int, size int, alignment text)
LANGUAGE plpgsql
STABLE
AS $$
DECLARE
    v_pairs   jsonb;
    v_item    jsonb;
    v_name    text;
    v_type    text;
    v_canon   text;
    v_size    jsonb;
    v_align   text;
    v_seen    text[] := '{}';
    v_i       int := 0;
BEGIN
    IF p_properties IS NULL OR p_properties = 'null'::jsonb THEN
        RETURN;
    END IF;
    CASE jsonb_typeof(p_properties)
        WHEN 'object' THEN
            SELECT coalesce(jsonb_agg(jsonb_build_array(key, value)), '[]') INTO v_pairs FROM jsonb_each(p_properties);
        WHEN 'array' THEN
            v_pairs := p_properties;
        ELSE
            RAISE EXCEPTION '% properties must be a JSON object {"name": "type"} or an array of [name, type] pairs, not %',
                    p_what, jsonb_typeof(p_properties)
                USING ERRCODE = 'TG103';
    END CASE;

    FOR v_item IN SELECT value FROM jsonb_array_elements(v_pairs) LOOP
        v_i := v_i + 1;
        IF jsonb_typeof(v_item) = 'array' AND jsonb_array_length(v_item) IN (2, 3) THEN
            v_name := v_item ->> 0;
            v_type := v_item ->> 1;
            v_size := v_item -> 2;
        ELSIF jsonb_typeof(v_item) = 'object' THEN
            v_name := v_item ->> 'name';
            v_type := v_item ->> 'type';
            v_size := v_item -> 'size';
            v_align := upper(btrim(v_item ->> 'alignment'));
        ELSE
            RAISE EXCEPTION '% property % is %, expected [name, type] or {"name": ..., "type": ...}', p_what, v_i, v_item
                USING ERRCODE = 'TG103';
        END IF;
        IF v_align IS NOT NULL AND (v_align NOT IN ('VERTEX', 'CELL') OR NOT p_per_cell) THEN
            RAISE EXCEPTION '% property % has alignment %: only vertex and cell properties have one, VERTEX or CELL',
                    p_what, quote_literal(v_name), quote_literal(v_item ->> 'alignment')
                USING ERRCODE = 'TG103',
                      HINT = 'e.g. {"name": "facies", "type": "integer", "alignment": "CELL"} for a value per cell';
        END IF;
        IF v_size IS NOT NULL AND v_size <> 'null'::jsonb
           AND (jsonb_typeof(v_size) <> 'number' OR v_size::numeric NOT BETWEEN 1 AND 1000
                OR v_size::numeric <> trunc(v_size::numeric)) THEN
            RAISE EXCEPTION '% property % has size %: the number of components is a whole number 1 .. 1000', p_what,
                    quote_literal(v_name), v_size
                USING ERRCODE = 'TG103', HINT = 'e.g. ["slip", "float8", 3] for a vector of 3 components per vertex';
        END IF;

        -- names keep their letter case (a file's "Porosity" stays "Porosity"): the columns are
        -- quoted identifiers everywhere tgsis names them (format %I, psycopg sql.Identifier)
        IF v_name IS NULL OR v_name !~ '^[A-Za-z][A-Za-z0-9_]{0,62}$' THEN
            RAISE EXCEPTION '% property name % is not allowed', p_what, coalesce(quote_literal(v_name), 'NULL')
                USING ERRCODE = 'TG101',
                      DETAIL = 'Names must be letters (either case, kept as given), digits and underscores, '
                               'start with a letter and have at most 63 characters.',
                      HINT = 'Names starting with "_" are reserved for tgsis columns (_geoid, _idx); in SQL, quote '
                             'names with capitals or that are keywords: SELECT "Porosity" FROM ...';
        END IF;
        IF v_name = ANY (v_seen) THEN
            RAISE EXCEPTION '% property % is given twice', p_what, quote_literal(v_name) USING ERRCODE = 'TG103';
        END IF;
        v_seen := v_seen || v_name;

        SELECT t.typename INTO v_canon
          FROM tgsis.property_types t
         WHERE t.typename = lower(btrim(v_type)) OR lower(btrim(v_type)) = ANY (t.aliases);
        IF v_canon IS NULL THEN
            RAISE EXCEPTION '% property % has type %, which is not allowed', p_what, quote_literal(v_name),
                    coalesce(quote_literal(v_type), 'NULL')
                USING ERRCODE = 'TG103',
                      HINT = (SELECT 'allowed: ' || string_agg(t.typename, ', ' ORDER BY t.typename)
                                FROM tgsis.property_types t WHERE t.per_cell OR NOT p_per_cell);
        END IF;
        IF p_per_cell AND NOT (SELECT t.per_cell FROM tgsis.property_types t WHERE t.typename = v_canon) THEN
            RAISE EXCEPTION '% property % has type %: vertex and cell properties must be numbers or booleans',
                    p_what, quote_literal(v_name), v_canon
                USING ERRCODE = 'TG103',
                      HINT = (SELECT 'allowed: ' || string_agg(t.typename, ', ' ORDER BY t.typename)
                                FROM tgsis.property_types t WHERE t.per_cell);
        END IF;
        size := coalesce(CASE WHEN v_size <> 'null'::jsonb THEN v_size::numeric::int END, 1);
        IF size > 1 AND NOT p_per_cell THEN
            RAISE EXCEPTION '% property % has size %: only vertex and cell properties may be vectors', p_what,
                    quote_literal(v_name), size
                USING ERRCODE = 'TG103';
        END IF;
        name := v_name;
        typename := v_canon;
        ord := v_i;
        alignment := v_align;
        v_align := NULL;
        RETURN NEXT;
    END LOOP;
END
$$;

COMMENT ON FUNCTION tgsis.property_columns(jsonb, boolean, text) IS
    'validate a property list (names of letters in either case, digits and underscores, kept as given; types from tgsis.property_types; sizes of vector vertex/cell properties) and return it as ordered (name, typename, ord, size, alignment) rows';

-- ==== core/comment_property_columns.sql ====
-- tgsis.comment_property_columns(schema, table, properties, what): COMMENT ON each property column of a class table.
CREATE FUNCTION tgsis.comment_property_columns(p_schema text, p_table text, p_properties jsonb, p_what text)
RETURNS void
LANGUAGE plpgsql
VOLATILE
AS $$
DECLARE
    v_prop jsonb;
BEGIN
    FOR v_prop IN SELECT * FROM jsonb_array_elements(p_properties) LOOP
        EXECUTE format('COMMENT ON COLUMN %I.%I.%I IS %L', p_schema, p_table, v_prop ->> 'name',
                       format('%s (%s%s)', p_what, v_prop ->> 'type',
                              CASE WHEN v_prop ? 'size' THEN format('[%s]: a vector of %s components', v_prop ->> 'size', v_prop ->> 'size') ELSE '' END));
    END LOOP;
END
$$;

COMMENT ON FUNCTION tgsis.comment_property_columns(text, text, jsonb, text) IS
    'comment each property column ([{"name", "type"}]) of a feature-class table as "<what> (<type>)"';

-- ==== core/time_key_columns.sql ====
-- tgsis.time_key_columns(time model): the time-key columns a class table of that model has between _geoid and the rest.
-- From the data model's registry row (tgsis.data_models.timekey).
CREATE FUNCTION tgsis.time_key_columns(p_time_model text)
RETURNS text
LANGUAGE sql
STABLE
PARALLEL SAFE
AS $$
    SELECT coalesce((SELECT string_agg(quote_ident(k ->> 'name') || ', ', '' ORDER BY i)
                       FROM tgsis.data_models m, jsonb_array_elements(m.timekey) WITH ORDINALITY AS e (k, i)
                      WHERE m.timemodel = upper(p_time_model)), '')
$$;

COMMENT ON FUNCTION tgsis.time_key_columns(text) IS
    'time-key column list ending in ", " of the class tables of a time model (tgsis.data_models.timekey): '''' (STATIC), ''_times, '' (INSTANTS), ''_timem, _timet, '' (EVOLVING)';

-- ==== core/comment_time_key_columns.sql ====
-- tgsis.comment_time_key_columns(schema, table, time model): COMMENT ON the time-key columns of a temporal class table.
-- The comments are the data model's (tgsis.data_models.timekey).
CREATE FUNCTION tgsis.comment_time_key_columns(p_schema text, p_table text, p_time_model text)
RETURNS void
LANGUAGE plpgsql
VOLATILE
AS $$
DECLARE
    v_key jsonb;
BEGIN
    FOR v_key IN SELECT k FROM tgsis.data_models m, jsonb_array_elements(m.timekey) AS k
                  WHERE m.timemodel = upper(p_time_model) LOOP
        EXECUTE format('COMMENT ON COLUMN %I.%I.%I IS %L', p_schema, p_table, v_key ->> 'name', v_key ->> 'comment');
    END LOOP;
END
$$;

COMMENT ON FUNCTION tgsis.comment_time_key_columns(text, text, text) IS
    'comment the time-key columns (tgsis.data_models.timekey: _times of INSTANTS, _timem and _timet of EVOLVING) of a temporal feature-class table';

-- ==== core/register_feature_class.sql ====
-- tgsis.register_feature_class(...): create a feature class (feature table, cell-property table, view) and catalog it.
-- A temporal class (time model INSTANTS = model 2, EVOLVING = model 3) holds
-- SURFACE features; it gets a per-instant property table <name>_pros, and the
-- time keys (_times, or _timem and _timet) in it and in <name>_cellpros.
-- It runs as tgsis's owner (SECURITY DEFINER), so that the class's tables,
-- views and generated functions are objects tgsis itself created: the
-- definer code that later versions them (enable_feature_versioning) acts only
-- on tables tgsis.catalog names, and only tgsis's definer code writes that.
-- The calling role must be a tgsis_admin with CREATE on the target schema; the
-- system schemas and tgsis's own are refused, and so are schemas of other
-- owners than tgsis's or a superuser (they could replace the class's tables).
CREATE FUNCTION tgsis.register_feature_class(
    p_name               text,
    p_geotype            text,
    p_feature_properties jsonb   DEFAULT '[]',
    p_cell_properties    jsonb   DEFAULT '[]',
    p_proalignment       text    DEFAULT 'VERTEX',
    p_srs                integer DEFAULT 0,
    p_schema             text    DEFAULT 'public',
    p_description        text    DEFAULT NULL,
    p_time_model         text    DEFAULT 'STATIC',
    p_instant_properties jsonb   DEFAULT '[]',
    p_time_unit          text    DEFAULT NULL,
    p_cell_level         integer DEFAULT NULL)
RETURNS tgsis.catalog
LANGUAGE plpgsql
VOLATILE
SECURITY DEFINER
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_geotype   text := upper(btrim(p_geotype));
    v_align     text := upper(btrim(p_proalignment));
    v_cellpros  text := p_name || '_cellpros';
    v_view      text := p_name || '_v';
    v_model     text := upper(btrim(p_time_model));
    v_dm        tgsis.data_models;
    v_temporal  boolean;
    v_pros      text;
    v_timekey   text;
    v_icols     text;
    v_iprops    jsonb;
    v_fcols     text;
    v_ccols     text;
    v_ocols     text;
    v_other     text;
    v_notnull   text;
    v_fprops    jsonb;
    v_cprops    jsonb;
    v_row       tgsis.catalog;
    v_caller    name := tgsis.calling_role();
    v_nspowner  oid;
BEGIN
    IF NOT pg_has_role(v_caller, 'tgsis_admin', 'MEMBER') THEN
        RAISE EXCEPTION 'role % may not register feature classes', v_caller
            USING ERRCODE = 'TG002', DETAIL = 'Registering feature classes is for members of tgsis_admin.',
                  HINT = format('a DBA may run: GRANT tgsis_admin TO %I', v_caller);
    END IF;
    IF p_name IS NULL OR p_name !~ '^[a-z][a-z0-9_]*$' OR quote_ident(p_name) <> p_name OR length(v_cellpros) > 63 THEN
        RAISE EXCEPTION 'feature class name % is not allowed', coalesce(quote_literal(p_name), 'NULL')
            USING ERRCODE = 'TG101',
                  DETAIL = 'A class name is also a table name: lower-case letters, digits and underscores, '
                           'starting with a letter, at most 54 characters, not an SQL keyword.';
    END IF;
    -- geotypes and time models are the registered data models' (tgsis.data_models)
    IF v_geotype IS NULL OR NOT EXISTS (SELECT FROM tgsis.data_models m WHERE v_geotype = ANY (m.geotypes)) THEN
        RAISE EXCEPTION 'unknown geotype % for feature class %', coalesce(quote_literal(p_geotype), 'NULL'), p_name
            USING ERRCODE = 'TG100',
                  HINT = tgsis.or_list(ARRAY(SELECT DISTINCT g FROM tgsis.data_models m, unnest(m.geotypes) AS g ORDER BY g));
    END IF;
    IF v_align IS NULL OR v_align NOT IN ('VERTEX', 'CELL') THEN
        RAISE EXCEPTION 'property alignment % of feature class % must be VERTEX or CELL',
                coalesce(quote_literal(p_proalignment), 'NULL'), p_name
            USING ERRCODE = 'TG100';
    END IF;
    SELECT * INTO v_dm FROM tgsis.data_models m WHERE m.timemodel = v_model;
    IF v_model IS NULL OR NOT FOUND THEN
        RAISE EXCEPTION 'time model % of feature class % must be %', coalesce(quote_literal(p_time_model), 'NULL'), p_name,
                        tgsis.or_list(ARRAY(SELECT m.timemodel FROM tgsis.data_models m WHERE m.model > 0 ORDER BY m.model))
            USING ERRCODE = 'TG100',
                  HINT = (SELECT string_agg(format('%s: %s (model %s)', m.timemodel, m.name, m.model), '; ' ORDER BY m.model)
                            FROM tgsis.data_models m WHERE m.model > 0);
    END IF;
    -- a temporal model is one whose class tables have a time key
    v_temporal := jsonb_array_length(v_dm.timekey) > 0;
    -- G-maps: properties belong to the cells of one level (the spec's cell level attach), _idx a cell id
    IF v_dm.cell_levels THEN
        IF p_cell_level IS NULL OR p_cell_level < 0 THEN
            RAISE EXCEPTION 'a % feature class needs the level of the cells its properties belong to, got %', v_model,
                    coalesce(p_cell_level::text, 'NULL')
                USING ERRCODE = 'TG100', HINT = 'p_cell_level => 0 (vertices), 1 (edges), 2 (faces), 3 (volumes), ...';
        END IF;
        v_align := 'CELL';
    ELSIF p_cell_level IS NOT NULL THEN
        RAISE EXCEPTION 'a % feature class attaches properties to vertices or simplices, not to cells of a level', v_model
            USING ERRCODE = 'TG100', HINT = 'leave p_cell_level out, or register a class of G-maps (p_time_model => ''GMAP'')';
    END IF;
    IF NOT v_geotype = ANY (v_dm.geotypes) THEN
        RAISE EXCEPTION 'a % feature class holds % features, not %', v_model, tgsis.or_list(v_dm.geotypes), v_geotype
            USING ERRCODE = 'TG100', HINT = format('time model %s (%s) is for %s', v_model, v_dm.name, tgsis.or_list(v_dm.geotypes));
    END IF;
    IF NOT v_temporal AND (p_time_unit IS NOT NULL OR coalesce(p_instant_properties, '[]') NOT IN ('[]', '{}')) THEN
        RAISE EXCEPTION 'static feature class % takes no time unit or per-instant properties', p_name
            USING ERRCODE = 'TG100',
                  HINT = format('give time_model => %s for a temporal class',
                                tgsis.or_list(ARRAY(SELECT quote_literal(m.timemodel) FROM tgsis.data_models m
                                                     WHERE jsonb_array_length(m.timekey) > 0 ORDER BY m.model)));
    END IF;
    IF v_temporal THEN
        v_pros := p_name || '_pros';
        SELECT string_agg(format('%I double precision NOT NULL, ', k ->> 'name'), '' ORDER BY i) INTO v_timekey
          FROM jsonb_array_elements(v_dm.timekey) WITH ORDINALITY AS e (k, i);
    END IF;
    IF p_srs IS NULL OR p_srs < 0 THEN
        RAISE EXCEPTION 'SRS % of feature class % must be an id >= 0 (0: undefined)', p_srs, p_name USING ERRCODE = 'TG100';
    END IF;
    -- tgsis's own schema would make tgsis's catalog tables and the class's look alike
    -- (enable_feature_versioning would then refuse to version them, for everyone)
    IF p_schema = ANY (ARRAY['tgsis', 'information_schema']) OR p_schema LIKE 'pg\_%' THEN
        RAISE EXCEPTION 'feature classes may not go into schema %', quote_literal(p_schema)
            USING ERRCODE = 'TG101', DETAIL = 'It is tgsis''s own schema or a system schema.',
                  HINT = 'choose a schema of your own, or leave the schema at its default (public)';
    END IF;
    IF p_schema IS NULL OR to_regnamespace(quote_ident(p_schema)) IS NULL THEN
        RAISE EXCEPTION 'schema % does not exist', coalesce(quote_literal(p_schema), 'NULL')
            USING ERRCODE = 'TG200', HINT = 'create it first, or leave the schema at its default (public)';
    END IF;
    -- a schema's owner may drop any table in it and put its own in its place,
    -- which tgsis's definer code would then act on as tgsis's owner
    SELECT CASE WHEN n.nspowner = 'pg_database_owner'::regrole THEN d.datdba ELSE n.nspowner END INTO v_nspowner
      FROM pg_namespace n, pg_database d WHERE n.nspname = p_schema AND d.datname = current_database();
    IF v_nspowner <> (SELECT relowner FROM pg_class WHERE oid = 'tgsis.catalog'::regclass)
       AND NOT (SELECT rolsuper FROM pg_roles WHERE oid = v_nspowner) THEN
        RAISE EXCEPTION 'schema % belongs to %, who could replace the tables of a feature class there', p_schema,
                pg_get_userbyid(v_nspowner)
            USING ERRCODE = 'TG002',
                  DETAIL = 'Feature classes go into schemas owned by tgsis''s owner or by a superuser.',
                  HINT = format('a superuser may run: ALTER SCHEMA %I OWNER TO %I', p_schema, current_user);
    END IF;
    IF NOT has_schema_privilege(v_caller, p_schema, 'CREATE') THEN
        RAISE EXCEPTION 'role % may not create tables in schema %', v_caller, p_schema
            USING ERRCODE = 'TG002', HINT = format('the schema''s owner may run: GRANT CREATE ON SCHEMA %I TO %I', p_schema, v_caller);
    END IF;
    IF NOT has_schema_privilege(current_user, p_schema, 'CREATE') THEN  -- tgsis's owner creates the tables
        RAISE EXCEPTION 'tgsis''s owner % may not create tables in schema %', current_user, p_schema
            USING ERRCODE = 'TG002', DETAIL = 'The tables of a feature class belong to tgsis''s owner.',
                  HINT = format('the schema''s owner may run: GRANT CREATE ON SCHEMA %I TO %I', p_schema, current_user);
    END IF;
    IF EXISTS (SELECT FROM tgsis.catalog WHERE classname = p_name) THEN
        RAISE EXCEPTION 'feature class % exists already', p_name
            USING ERRCODE = 'TG201', HINT = 'tgsis.drop_feature_class removes it';
    END IF;
    IF to_regclass(format('%I.%I', p_schema, p_name)) IS NOT NULL
       OR to_regclass(format('%I.%I', p_schema, v_cellpros)) IS NOT NULL
       OR to_regclass(format('%I.%I', p_schema, v_view)) IS NOT NULL
       OR to_regclass(format('%I.%I', p_schema, coalesce(v_pros, v_cellpros))) IS NOT NULL THEN
        RAISE EXCEPTION 'a table or view named %, %, % or % exists already in schema %',
                p_name, v_cellpros, v_view, coalesce(v_pros, p_name || '_pros'), p_schema
            USING ERRCODE = 'TG201';
    END IF;

    SELECT coalesce(string_agg(format(', %I %s', name, typename), '' ORDER BY ord), ''),
           coalesce(jsonb_agg(jsonb_build_object('name', name, 'type', typename) ORDER BY ord), '[]')
      INTO v_fcols, v_fprops
      FROM tgsis.property_columns(p_feature_properties, false, 'feature');
    v_notnull := CASE WHEN v_geotype = 'GEOMETRYCOLLECTION' THEN '' ELSE ' NOT NULL' END;
    -- a vector property (size k > 1) is one column holding an array of exactly k values; a
    -- property aligned otherwise than the class (alignment is per property) goes to v_other
    WITH props AS (
        SELECT p.name, p.ord, p.size, nullif(p.alignment, v_align) AS alignment,
               -- a collection's members may each have some of the class's properties: the rows of a
               -- member hold NULL in the columns of properties it lacks
               CASE WHEN p.size = 1 THEN format(', %I %s%s', p.name, p.typename, v_notnull)
                    ELSE format(', %I %s[]%s CHECK (array_ndims(%I) = 1 AND array_lower(%I, 1) = 1 '
                                'AND cardinality(%I) = %s AND array_position(%I, NULL) IS NULL)',
                                p.name, p.typename, v_notnull, p.name, p.name, p.name, p.size, p.name) END AS definition,
               jsonb_build_object('name', p.name, 'type', p.typename) AS item
          FROM tgsis.property_columns(p_cell_properties, true, lower(v_align)) p)
    SELECT coalesce(string_agg(definition, '' ORDER BY ord) FILTER (WHERE alignment IS NULL), ''),
           string_agg(definition, '' ORDER BY ord) FILTER (WHERE alignment IS NOT NULL),
           coalesce(jsonb_agg(item || CASE WHEN size > 1 THEN jsonb_build_object('size', size) ELSE '{}' END
                                   || CASE WHEN alignment IS NOT NULL THEN jsonb_build_object('alignment', alignment)
                                           ELSE '{}' END ORDER BY ord), '[]')
      INTO v_ccols, v_ocols, v_cprops
      FROM props;
    IF v_temporal AND EXISTS (SELECT FROM jsonb_array_elements(v_cprops) p WHERE p ? 'size' OR p ? 'alignment') THEN
        RAISE EXCEPTION 'temporal feature class % takes no vector properties nor properties of another alignment', p_name
            USING ERRCODE = 'TG103', HINT = 'give one scalar property per component, all of the class''s alignment';
    END IF;
    IF v_ocols IS NOT NULL THEN
        v_other := p_name || CASE v_align WHEN 'VERTEX' THEN '_simplexpros' ELSE '_vertexpros' END;
        IF length(v_other) > 63 THEN
            RAISE EXCEPTION 'feature class name % is too long for a class with vertex and cell properties', p_name
                USING ERRCODE = 'TG101', DETAIL = format('Its table %s would have more than 63 characters.', v_other);
        END IF;
        IF to_regclass(format('%I.%I', p_schema, v_other)) IS NOT NULL THEN
            RAISE EXCEPTION 'a table or view named % exists already in schema %', v_other, p_schema USING ERRCODE = 'TG201';
        END IF;
    END IF;
    SELECT coalesce(string_agg(format(', %I %s', name, typename), '' ORDER BY ord), ''),
           coalesce(jsonb_agg(jsonb_build_object('name', name, 'type', typename) ORDER BY ord), '[]')
      INTO v_icols, v_iprops
      FROM tgsis.property_columns(p_instant_properties, false, 'per-instant');

    IF EXISTS (SELECT FROM tgsis.versioned_tables WHERE schemaname = 'tgsis' AND tablename = 'geometry') THEN
        -- model 1 is versioned: the key to tgsis.geometry cannot hold across
        -- versions; record it as versioning would have dropped it
        EXECUTE format('CREATE TABLE %I.%I (_geoid bigint PRIMARY KEY%s)', p_schema, p_name, v_fcols);
        INSERT INTO tgsis.versioning_dropped (schemaname, tablename, name, definition, refschema, reftable, dropped_for)
        VALUES (p_schema, p_name, p_name || '__geoid_fkey',
                'FOREIGN KEY (_geoid) REFERENCES tgsis.geometry(geoid) ON DELETE CASCADE', 'tgsis', 'geometry',
                format('%I.%I', p_schema, p_name));
    ELSE
        EXECUTE format('CREATE TABLE %I.%I (_geoid bigint PRIMARY KEY REFERENCES tgsis.geometry (geoid) ON DELETE CASCADE%s)',
                       p_schema, p_name, v_fcols);
    END IF;
    -- no foreign key to the feature table: a per-row check would dominate bulk uploads
    EXECUTE format('CREATE TABLE %I.%I (_geoid bigint NOT NULL, %s_idx bigint NOT NULL%s, PRIMARY KEY (_geoid, %s_idx))',
                   p_schema, v_cellpros, coalesce(v_timekey, ''), v_ccols, tgsis.time_key_columns(v_model));
    IF v_pros IS NOT NULL THEN
        EXECUTE format('CREATE TABLE %I.%I (_geoid bigint NOT NULL, %s%s, PRIMARY KEY (_geoid, %s))',
                       p_schema, v_pros, rtrim(v_timekey, ', '), v_icols, rtrim(tgsis.time_key_columns(v_model), ', '));
        EXECUTE format('COMMENT ON TABLE %I.%I IS %L', p_schema, v_pros,
                       format('tgsis feature class %s: per-instant feature properties (%s)', p_name,
                              format('one row per feature and %s', rtrim(tgsis.time_key_columns(v_model), ', '))));
        EXECUTE format('COMMENT ON COLUMN %I.%I._geoid IS %L', p_schema, v_pros, 'the feature (_geoid of ' || p_name || ')');
        PERFORM tgsis.comment_time_key_columns(p_schema, v_pros, v_model);
        PERFORM tgsis.comment_property_columns(p_schema, v_pros, v_iprops, 'per-instant feature property');
        EXECUTE format('GRANT SELECT ON %I.%I TO tgsis_reader', p_schema, v_pros);
        EXECUTE format('GRANT INSERT, UPDATE, DELETE ON %I.%I TO tgsis_editor', p_schema, v_pros);
        PERFORM tgsis.comment_time_key_columns(p_schema, v_cellpros, v_model);
    END IF;

    EXECUTE format('COMMENT ON TABLE %I.%I IS %L', p_schema, p_name,
                   format('tgsis feature class %s: one row per %s feature (_geoid = tgsis.geometry.geoid)', p_name, v_geotype));
    EXECUTE format('COMMENT ON COLUMN %I.%I._geoid IS %L', p_schema, p_name, 'the feature''s geometry (tgsis.geometry.geoid)');
    -- a collection's properties belong to its members: _geoid is a member geometry, not the feature
    EXECUTE format('COMMENT ON TABLE %I.%I IS %L', p_schema, v_cellpros,
                   format('tgsis feature class %s: %s properties (%s_idx = %s)', p_name, lower(v_align),
                          CASE WHEN v_geotype = 'GEOMETRYCOLLECTION' THEN '_geoid = member geometry, ' ELSE '' END,
                          CASE WHEN v_dm.cell_levels THEN format('abstract cell id of a %s-cell', p_cell_level)
                               WHEN v_align = 'VERTEX' THEN 'tgsis.vrtx.vrtxid'
                               WHEN v_geotype = 'GEOMETRYCOLLECTION' THEN 'simplex id in the member''s point/segment/trgl/tetra'
                               ELSE format('tgsis.%s id', tgsis.simplex_table(v_geotype)) END));
    EXECUTE format('COMMENT ON COLUMN %I.%I._geoid IS %L', p_schema, v_cellpros,
                   CASE WHEN v_geotype = 'GEOMETRYCOLLECTION'
                        THEN 'a member geometry (tgsis.geometry.geoid) of a feature of ' || p_name
                        ELSE 'the feature (_geoid of ' || p_name || ')' END);
    EXECUTE format('COMMENT ON COLUMN %I.%I._idx IS %L', p_schema, v_cellpros,
                   CASE WHEN v_dm.cell_levels THEN format('abstract cell id (acellid) of a %s-cell', p_cell_level)
                        WHEN v_align = 'VERTEX' THEN 'vertex id (vrtxid)' ELSE 'simplex id' END);
    PERFORM tgsis.comment_property_columns(p_schema, p_name, v_fprops, 'per-feature property');
    PERFORM tgsis.comment_property_columns(p_schema, v_cellpros,
                                           (SELECT coalesce(jsonb_agg(p), '[]') FROM jsonb_array_elements(v_cprops) p
                                             WHERE NOT p ? 'alignment'),
                                           format('%s property', lower(v_align)));

    IF v_other IS NOT NULL THEN  -- the properties of the other alignment: the same keys, _idx of the other kind
        EXECUTE format('CREATE TABLE %I.%I (_geoid bigint NOT NULL, _idx bigint NOT NULL%s, PRIMARY KEY (_geoid, _idx))',
                       p_schema, v_other, v_ocols);
        EXECUTE format('COMMENT ON TABLE %I.%I IS %L', p_schema, v_other,
                       format('tgsis feature class %s: %s properties (%s_idx = %s)', p_name,
                              CASE v_align WHEN 'VERTEX' THEN 'cell' ELSE 'vertex' END,
                              CASE WHEN v_geotype = 'GEOMETRYCOLLECTION' THEN '_geoid = member geometry, ' ELSE '' END,
                              CASE WHEN v_align = 'CELL' THEN 'tgsis.vrtx.vrtxid'
                                   WHEN v_geotype = 'GEOMETRYCOLLECTION' THEN 'simplex id in the member''s point/segment/trgl/tetra'
                                   ELSE format('tgsis.%s id', tgsis.simplex_table(v_geotype)) END));
        EXECUTE format('COMMENT ON COLUMN %I.%I._geoid IS %L', p_schema, v_other,
                       CASE WHEN v_geotype = 'GEOMETRYCOLLECTION'
                            THEN 'a member geometry (tgsis.geometry.geoid) of a feature of ' || p_name
                            ELSE 'the feature (_geoid of ' || p_name || ')' END);
        EXECUTE format('COMMENT ON COLUMN %I.%I._idx IS %L', p_schema, v_other,
                       CASE v_align WHEN 'CELL' THEN 'vertex id (vrtxid)' ELSE 'simplex id' END);
        PERFORM tgsis.comment_property_columns(p_schema, v_other,
                                               (SELECT jsonb_agg(p) FROM jsonb_array_elements(v_cprops) p WHERE p ? 'alignment'),
                                               CASE v_align WHEN 'VERTEX' THEN 'cell property' ELSE 'vertex property' END);
        EXECUTE format('GRANT SELECT ON %I.%I TO tgsis_reader', p_schema, v_other);
        EXECUTE format('GRANT INSERT, UPDATE, DELETE ON %I.%I TO tgsis_editor', p_schema, v_other);
    END IF;
    EXECUTE format('GRANT SELECT ON %I.%I, %I.%I TO tgsis_reader', p_schema, p_name, p_schema, v_cellpros);
    EXECUTE format('GRANT INSERT, UPDATE, DELETE ON %I.%I, %I.%I TO tgsis_editor', p_schema, p_name, p_schema, v_cellpros);

    INSERT INTO tgsis.catalog (classname, schemaname, geotype, featuretable, cellprotable, otherprotable, viewname,
                               protablename, timemodel, timeunit, proalignment, srs, feature_properties, cell_properties,
                               instant_properties, description, created_by, celllevel)
    VALUES (p_name, p_schema, v_geotype, p_name, v_cellpros, v_other, v_view, v_pros, v_model, p_time_unit, v_align, p_srs,
            v_fprops, v_cprops, v_iprops, p_description, v_caller, p_cell_level)
    RETURNING * INTO v_row;
    -- once model 1 is versioned, every new class is versioned with it
    IF EXISTS (SELECT FROM tgsis.versioned_tables WHERE schemaname = 'tgsis' AND tablename = 'geometry') THEN
        PERFORM tgsis.version_class_tables(p_name);
    END IF;
    PERFORM tgsis.create_class_view(p_name);
    RETURN v_row;
END
$$;

COMMENT ON FUNCTION tgsis.register_feature_class(text, text, jsonb, jsonb, text, integer, text, text, text, jsonb, text, integer) IS
    'register a feature class (tgsis_admin members with CREATE on the schema; the tables belong to tgsis''s owner): creates <schema>.<name> (features), <name>_cellpros (vertex/cell properties of the class''s alignment), <name>_simplexpros or <name>_vertexpros (properties of the other alignment, if any), <name>_v (view) and for temporal classes (INSTANTS, EVOLVING) <name>_pros (per-instant properties); records it in tgsis.catalog';

-- ==== core/create_class_view.sql ====
-- tgsis.create_class_view(class): (re)create the view <class>_v joining a class's features with their geometry rows.
CREATE FUNCTION tgsis.create_class_view(p_class text)
RETURNS void
LANGUAGE plpgsql
VOLATILE
AS $$
DECLARE
    v_class  tgsis.catalog := tgsis.catalog_row(p_class);
    v_column record;
BEGIN
    EXECUTE format('DROP VIEW IF EXISTS %I.%I', v_class.schemaname, v_class.viewname);
    EXECUTE format('CREATE VIEW %I.%I AS SELECT g.geoname, f.*, g.geotype, g.nvrtx, g.ncell, g.bbox, g.created_at
                      FROM %I.%I f JOIN tgsis.geometry g ON g.geoid = f._geoid',
                   v_class.schemaname, v_class.viewname, v_class.schemaname, v_class.featuretable);
    EXECUTE format('COMMENT ON VIEW %I.%I IS %L', v_class.schemaname, v_class.viewname,
                   format('tgsis feature class %s: features with their name, geotype, counts and bounding box', p_class));
    -- the view's columns mean what they mean in the feature table and tgsis.geometry
    EXECUTE format('COMMENT ON COLUMN %I.%I.geoname IS %L', v_class.schemaname, v_class.viewname, 'name of the feature''s geometry');
    FOR v_column IN
        SELECT a.attname, coalesce(col_description(format('%I.%I', v_class.schemaname, v_class.featuretable)::regclass, f.attnum),
                                   col_description('tgsis.geometry'::regclass, g.attnum)) AS note
          FROM pg_catalog.pg_attribute a
          LEFT JOIN pg_catalog.pg_attribute f ON f.attrelid = format('%I.%I', v_class.schemaname, v_class.featuretable)::regclass
                                              AND f.attname = a.attname
          LEFT JOIN pg_catalog.pg_attribute g ON g.attrelid = 'tgsis.geometry'::regclass AND g.attname = a.attname
         WHERE a.attrelid = format('%I.%I', v_class.schemaname, v_class.viewname)::regclass AND a.attnum > 0
           AND a.attname <> 'geoname'
    LOOP
        EXECUTE format('COMMENT ON COLUMN %I.%I.%I IS %L', v_class.schemaname, v_class.viewname, v_column.attname, v_column.note);
    END LOOP;
    EXECUTE format('GRANT SELECT ON %I.%I TO tgsis_reader', v_class.schemaname, v_class.viewname);
END
$$;

COMMENT ON FUNCTION tgsis.create_class_view(text) IS
    '(re)create <class>_v: the class''s features joined with tgsis.geometry (name, geotype, counts, bbox), for psql users';

-- ==== core/drop_feature_class.sql ====
-- tgsis.drop_feature_class(name, force): remove a feature class; with force also its features and their geometries.
-- Table definitions are not versioned: a class is dropped in every version,
-- so its features' rows go from the storage of every version too.
-- A collection's owned members go with it, their cell properties with the table.
-- It runs as tgsis's owner (SECURITY DEFINER), who owns the class's tables
-- (see register_feature_class), for members of tgsis_admin.
CREATE FUNCTION tgsis.drop_feature_class(p_name text, p_force boolean DEFAULT false)
RETURNS bigint
LANGUAGE plpgsql
VOLATILE
SECURITY DEFINER
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_class tgsis.catalog;
    v_count bigint;
    v_ids   bigint[];
    v_table text;
    v_all   bigint[];
BEGIN
    IF NOT pg_has_role(tgsis.calling_role(), 'tgsis_admin', 'MEMBER') THEN
        RAISE EXCEPTION 'role % may not drop feature classes', tgsis.calling_role()
            USING ERRCODE = 'TG002', DETAIL = 'Dropping feature classes is for members of tgsis_admin.',
                  HINT = format('a DBA may run: GRANT tgsis_admin TO %I', tgsis.calling_role());
    END IF;
    SELECT * INTO v_class FROM tgsis.catalog WHERE classname = p_name FOR UPDATE;
    IF NOT FOUND THEN
        RAISE EXCEPTION 'feature class % does not exist', coalesce(quote_literal(p_name), 'NULL')
            USING ERRCODE = 'TG200', HINT = 'SELECT classname FROM tgsis.catalog lists the classes';
    END IF;
    -- its PostGIS view, if tgsis.create_postgis_view made one (sql/postgis/create_postgis_view.sql)
    IF (SELECT obj_description(c.oid, 'pg_class') LIKE 'tgsis PostGIS view %' AND c.relkind = 'v'
               AND c.relowner = (SELECT relowner FROM pg_class WHERE oid = 'tgsis.catalog'::regclass)
          FROM pg_class c WHERE c.oid = to_regclass(format('%I.%I', v_class.schemaname, v_class.classname || '_postgis'))) THEN
        EXECUTE format('DROP VIEW %I.%I', v_class.schemaname, v_class.classname || '_postgis');
    END IF;
    EXECUTE format('SELECT count(DISTINCT _geoid), array_agg(DISTINCT _geoid) FROM %s',
                   tgsis.storage_table(v_class.schemaname, v_class.featuretable))
       INTO v_count, v_ids;
    IF v_count > 0 AND NOT p_force THEN
        RAISE EXCEPTION 'feature class % still has % feature(s)', p_name, v_count
            USING ERRCODE = 'TG202',
                  DETAIL = 'Features stored in any version count.',
                  HINT = 'delete them first, or drop with force => true to delete them with their geometries';
    END IF;
    IF v_count > 0 THEN
        -- the features' geometries and the collection members they own (not geometries a collection only lists)
        EXECUTE format('SELECT $1 || coalesce(array_agg(DISTINCT geoid), ''{}'') FROM %s WHERE collection = ANY ($1)',
                       tgsis.storage_table('tgsis', 'geometry'))
           INTO v_all USING v_ids;
        PERFORM tgsis.delete_stored_geometries(v_all);
    END IF;
    EXECUTE format('DROP VIEW %I.%I', v_class.schemaname, v_class.viewname);
    FOR v_table IN SELECT t.tablename FROM tgsis.class_tables t WHERE t.classname = p_name ORDER BY t.position DESC LOOP
        IF EXISTS (SELECT FROM tgsis.versioned_tables WHERE schemaname = v_class.schemaname AND tablename = v_table) THEN
            EXECUTE format('DROP VIEW %I.%I', v_class.schemaname, v_table);
            EXECUTE format('DROP FUNCTION %I.%I()', v_class.schemaname, v_table || '_ver_write');
            EXECUTE format('DROP FUNCTION IF EXISTS %I.%I(boolean, text, text[], integer[], integer[], integer, bigint[])',
                           v_class.schemaname, v_table || '_ver_run');
            EXECUTE format('DROP TABLE %I.%I', v_class.schemaname, v_table || '_ver');
            DELETE FROM tgsis.versioned_tables WHERE schemaname = v_class.schemaname AND tablename = v_table;
            DELETE FROM tgsis.versioning_dropped WHERE schemaname = v_class.schemaname AND tablename = v_table;
        ELSE
            EXECUTE format('DROP TABLE %I.%I', v_class.schemaname, v_table);
        END IF;
    END LOOP;
    DELETE FROM tgsis.catalog WHERE classname = p_name;
    RETURN v_count;
END
$$;

COMMENT ON FUNCTION tgsis.drop_feature_class(text, boolean) IS
    'drop a feature class and its tables (tgsis_admin members) (in every version); refuses (TG202) while features exist unless force, which deletes them and their geometries (with the members collections own); returns the number of features deleted';

-- ==== checkin/feature_write_lock.sql ====
-- tgsis.feature_write_lock(geoid): serialise writers of one stored feature until the transaction ends.
-- The object write lock (tgsis.object_write_lock) of object class 'feature':
-- check-in, save and delete of the feature take it before they look at it,
-- so that two of them never both decide from the same state, and writes
-- through the versioned views (which hold it shared) are never in flight
-- meanwhile. With feature versioning off, raw SQL writes on the plain tables
-- take no lock: they are not seen (docs/comparison.md).
CREATE FUNCTION tgsis.feature_write_lock(p_geoid bigint)
RETURNS void
LANGUAGE sql
VOLATILE
AS $$
    SELECT tgsis.object_write_lock('feature', ARRAY[p_geoid::text])
$$;

COMMENT ON FUNCTION tgsis.feature_write_lock(bigint) IS
    'take the exclusive object write lock of a feature (tgsis.object_write_lock(''feature'', ...)) that check-in, save and delete hold while they decide from its state';

-- ==== geometry/delete_stored_geometries.sql ====
-- tgsis.delete_stored_geometries(geoids): physically remove geometries from the storage of every version.
-- For dropping a whole feature class, which is not a versioned change.
CREATE FUNCTION tgsis.delete_stored_geometries(p_geoids bigint[])
RETURNS void
LANGUAGE plpgsql
VOLATILE
AS $$
DECLARE
    v_table text;
BEGIN
    -- every registered storage table, tgsis.geometry last
    FOR v_table IN SELECT tablename FROM tgsis.model_tables WHERE geoidcolumn IS NOT NULL
                    ORDER BY model = 0, iudorder DESC, tablename LOOP
        EXECUTE format('DELETE FROM %s WHERE geoid = ANY ($1)', tgsis.storage_table('tgsis', v_table)) USING p_geoids;
    END LOOP;
END
$$;

COMMENT ON FUNCTION tgsis.delete_stored_geometries(bigint[]) IS
    'physically delete geometries from every registered storage table (tgsis.model_tables) of all versions, tgsis.geometry last; used when a feature class is dropped';

-- ==== geometry/model_tables_of.sql ====
-- tgsis.model_tables_of(geoids): the registered storage tables holding rows of these geometries, children first.
-- What deleting geometries must empty: the tables of their models (those of a
-- geotype only when one of them has it), then the geometry core. One place
-- that turns the registry into a deletion order, for tgsis.delete_geometry.
CREATE FUNCTION tgsis.model_tables_of(p_geoids bigint[])
RETURNS SETOF text
LANGUAGE plpgsql
STABLE
AS $$
BEGIN
    -- (PL/pgSQL: the storage tables do not exist yet when the extension script runs)
    RETURN QUERY
    SELECT t.tablename
      FROM tgsis.model_tables t
     WHERE t.geoidcolumn IS NOT NULL
       AND (t.model = 0
        OR EXISTS (SELECT FROM tgsis.geometry g JOIN tgsis.data_models m ON m.timemodel = g.timemodel
                    WHERE g.geoid = ANY (p_geoids) AND m.model = t.model
                      AND (t.geotype IS NULL OR t.geotype = g.geotype)))
     ORDER BY t.model = 0, t.tablename = 'geometry', t.iudorder DESC, t.tablename;
END
$$;

COMMENT ON FUNCTION tgsis.model_tables_of(bigint[]) IS
    'storage tables (tgsis.model_tables) that may hold rows of these geometries, in deletion order: the models'' tables children first, tgsis.geometry last';

-- ==== geometry/delete_geometry.sql ====
-- tgsis.delete_geometry(geoid): remove a geometry with its vertices, simplices, feature row, cell properties and owned members.
-- A GEOMETRYCOLLECTION takes the members it owns (tgsis.geometry.collection)
-- with it, each with its rows; geometries it only lists in geoids stay.
-- Members cannot be collections, so one level is the whole recursion.
-- Works in the session's version: on versioned tables the rows are closed
-- set-based (tgsis.delete_object_rows), not one trigger call per vertex.
CREATE FUNCTION tgsis.delete_geometry(p_geoid bigint)
RETURNS boolean
LANGUAGE plpgsql
AS $$
DECLARE
    v_geo   record;
    v_ids   bigint[];
    v_class record;
    v_table text;
BEGIN
    PERFORM tgsis.plain_write_check('tgsis', 'geometry');  -- not "in" a version while features are plain
    PERFORM tgsis.feature_write_lock(p_geoid);  -- a check-in deciding from this object's state finishes first
    SELECT geotype, collection, timemodel INTO v_geo FROM tgsis.geometry WHERE geoid = p_geoid FOR UPDATE;
    IF NOT FOUND THEN
        RETURN false;
    END IF;
    IF v_geo.collection IS NOT NULL THEN
        RAISE EXCEPTION 'geometry % is a member of collection % and is deleted only with it', p_geoid, v_geo.collection
            USING ERRCODE = 'TG202',
                  HINT = format('SELECT tgsis.delete_geometry(%s) deletes the collection with its members', v_geo.collection);
    END IF;
    -- members first, the collection last (its row is what owns them)
    SELECT coalesce(array_agg(geoid ORDER BY geoid), '{}') || p_geoid INTO v_ids
      FROM tgsis.geometry WHERE collection = p_geoid;
    -- the feature row: its foreign key is gone once model 1 is versioned, so
    -- delete it explicitly; cell properties of a collection's members are in
    -- its class's table, keyed by member geoid
    FOR v_class IN SELECT t.schemaname, t.tablename, t.kind FROM tgsis.class_tables t JOIN tgsis.catalog c USING (classname)
                    WHERE c.geotype = v_geo.geotype AND c.timemodel = v_geo.timemodel ORDER BY t.classname, t.position DESC LOOP
        PERFORM tgsis.delete_object_rows(v_class.schemaname, v_class.tablename, '_geoid',
                                         CASE v_class.kind WHEN 'feature' THEN ARRAY[p_geoid] ELSE v_ids END);
    END LOOP;
    -- the storage of their models, tgsis.geometry last (tgsis.model_tables_of)
    FOR v_table IN SELECT * FROM tgsis.model_tables_of(v_ids) LOOP
        PERFORM tgsis.delete_object_rows('tgsis', v_table, 'geoid', v_ids);
    END LOOP;
    RETURN true;
END
$$;

COMMENT ON FUNCTION tgsis.delete_geometry(bigint) IS
    'delete a geometry with its rows in its data model''s tables (tgsis.model_tables: vertices, simplices, atoms, parts; instants and periods of temporal ones), its feature row, cell and per-instant properties (tgsis.class_tables), and the members a collection owns (not those it only lists), in the session''s version; refuses (TG202) an owned member; false if it did not exist';

-- ==== versioning/version_class_tables.sql ====
-- tgsis.version_class_tables(class): version a feature class's tables as part of object class 'feature'.
-- Its tables are tgsis.class_tables's rows; the feature table comes before
-- the property tables that refer to its features (iudorder 3, then 4).
CREATE FUNCTION tgsis.version_class_tables(p_class text)
RETURNS void
LANGUAGE plpgsql
VOLATILE
AS $$
DECLARE
    v_class tgsis.catalog := tgsis.catalog_row(p_class);
    v_table record;
BEGIN
    EXECUTE format('DROP VIEW IF EXISTS %I.%I', v_class.schemaname, v_class.viewname);  -- re-created over the versioned views
    FOR v_table IN SELECT t.schemaname, t.tablename, t.kind FROM tgsis.class_tables t
                    WHERE t.classname = p_class ORDER BY t.position LOOP
        CONTINUE WHEN EXISTS (SELECT FROM tgsis.versioned_tables
                               WHERE schemaname = v_table.schemaname AND tablename = v_table.tablename);
        PERFORM tgsis.enable_versioning_rel(format('%I.%I', v_table.schemaname, v_table.tablename)::regclass,
                                            '_geoid', 'feature', CASE v_table.kind WHEN 'feature' THEN 3 ELSE 4 END,
                                            v_table.schemaname || '.' || v_table.tablename);
    END LOOP;
END
$$;

COMMENT ON FUNCTION tgsis.version_class_tables(text) IS
    'version the tables of a feature class (tgsis.class_tables: feature, cell-property of both alignments, per-instant property) in object class ''feature'', keyed by _geoid; drops <class>_v for the caller to re-create';

-- ==== modelsets/model_id.sql ====
-- tgsis.model_id(name): the id of the model called name in the session's version; TG200 naming it when there is none.
-- Models are named sets of objects (tgsis.model); the writers and readers
-- below take a name, as people do.
CREATE FUNCTION tgsis.model_id(p_name text)
RETURNS bigint
LANGUAGE plpgsql
STABLE
SET search_path FROM CURRENT
AS $$
DECLARE
    v_id bigint;
BEGIN
    SELECT m.modelid INTO v_id FROM tgsis.model m WHERE m.name = p_name;
    IF NOT FOUND THEN
        RAISE EXCEPTION 'model % does not exist in version %', coalesce(quote_literal(p_name), 'NULL'),
                        tgsis.get_working_version()
            USING ERRCODE = 'TG200', HINT = 'SELECT name FROM tgsis.model lists the models';
    END IF;
    RETURN v_id;
END
$$;

COMMENT ON FUNCTION tgsis.model_id(text) IS 'id of the model called name in the session''s version; TG200 when there is none';

-- ==== modelsets/checked_objects.sql ====
-- tgsis.checked_objects(objects): the distinct ids, each a stored object (a feature's geometry); TG200 naming the missing ones.
-- A model's members must be objects the session's version holds, not
-- members of collections (which belong to their collection) nor unknown ids.
CREATE FUNCTION tgsis.checked_objects(p_objects bigint[])
RETURNS bigint[]
LANGUAGE plpgsql
STABLE
SET search_path FROM CURRENT
AS $$
DECLARE
    v_missing bigint[];
BEGIN
    IF p_objects IS NULL OR array_position(p_objects, NULL) IS NOT NULL THEN
        RAISE EXCEPTION 'the objects of a model are feature ids, got %', coalesce(p_objects::text, 'NULL')
            USING ERRCODE = 'TG100', HINT = 'p_objects => ''{12, 13}''';
    END IF;
    SELECT array_agg(o ORDER BY o) INTO v_missing
      FROM (SELECT DISTINCT o FROM unnest(p_objects) o) u
     WHERE NOT EXISTS (SELECT FROM tgsis.geometry g WHERE g.geoid = u.o AND g.collection IS NULL);
    IF v_missing IS NOT NULL THEN
        RAISE EXCEPTION 'objects % are not stored features in version %', v_missing, tgsis.get_working_version()
            USING ERRCODE = 'TG200', HINT = 'SELECT geoid FROM tgsis.geometry lists the stored geometries';
    END IF;
    RETURN ARRAY(SELECT DISTINCT o FROM unnest(p_objects) o ORDER BY o);
END
$$;

COMMENT ON FUNCTION tgsis.checked_objects(bigint[]) IS
    'the distinct ids, ascending, when each is a stored object (not a collection member) in the session''s version; TG200 naming the others';

-- ==== modelsets/feature_of_class.sql ====
-- tgsis.feature_of_class(class, geoid): whether the class's feature table has the feature (through its name: the session's version).
CREATE FUNCTION tgsis.feature_of_class(p_class text, p_geoid bigint)
RETURNS boolean
LANGUAGE plpgsql
STABLE
SET search_path FROM CURRENT
AS $$
DECLARE
    v_class tgsis.catalog := tgsis.catalog_row(p_class);
    v_found boolean;
BEGIN
    EXECUTE format('SELECT EXISTS (SELECT FROM %I.%I WHERE _geoid = $1)', v_class.schemaname, v_class.featuretable)
       INTO v_found USING p_geoid;
    RETURN v_found;
END
$$;

COMMENT ON FUNCTION tgsis.feature_of_class(text, bigint) IS 'whether feature class p_class has the feature p_geoid in the session''s version';

-- ==== modelsets/create_model.sql ====
-- tgsis.create_model(name, objects, description): a new model, a named set of objects, in the session's version; returns its id.
-- A model's name is unique in each version (two sessions creating one name
-- take turns on a transaction lock of the name, the second is refused).
-- Its rows are written through the tables' names: with versioning on, in
-- the session's version (the model and each object's membership are
-- versioned rows); one statement each, one transaction.
CREATE FUNCTION tgsis.create_model(p_name text, p_objects bigint[] DEFAULT '{}', p_description text DEFAULT NULL)
RETURNS bigint
LANGUAGE plpgsql
VOLATILE
SET search_path FROM CURRENT
AS $$
DECLARE
    v_objects bigint[];
    v_id      bigint;
BEGIN
    PERFORM tgsis.plain_write_check('tgsis', 'model');
    IF p_name IS NULL OR btrim(p_name) = '' THEN
        RAISE EXCEPTION 'a model needs a name, got %', coalesce(quote_literal(p_name), 'NULL')
            USING ERRCODE = 'TG101', HINT = 'p_name => ''resource model 2024''';
    END IF;
    v_objects := tgsis.checked_objects(p_objects);
    PERFORM pg_advisory_xact_lock(hashtextextended('tgsis.model ' || p_name, 0));
    IF EXISTS (SELECT FROM tgsis.model m WHERE m.name = p_name) THEN
        RAISE EXCEPTION 'model % exists already in version %', quote_literal(p_name), tgsis.get_working_version()
            USING ERRCODE = 'TG201', HINT = 'choose another name, or add objects to it (tgsis.add_to_model)';
    END IF;
    INSERT INTO tgsis.model (name, description) VALUES (p_name, p_description) RETURNING modelid INTO v_id;
    INSERT INTO tgsis.model_object (geoid, modelid) SELECT o, v_id FROM unnest(v_objects) o;
    RETURN v_id;
END
$$;

COMMENT ON FUNCTION tgsis.create_model(text, bigint[], text) IS
    'create a model (a named set of objects, unique by name in the session''s version) with these stored objects; returns its id';

-- ==== modelsets/add_to_model.sql ====
-- tgsis.add_to_model(name, objects): put stored objects into a model (those already in it stay); returns how many were added.
-- An object may belong to several models; the membership is a row of the
-- object's (versioned with it, deleted with it).
CREATE FUNCTION tgsis.add_to_model(p_name text, p_objects bigint[])
RETURNS bigint
LANGUAGE plpgsql
VOLATILE
SET search_path FROM CURRENT
AS $$
DECLARE
    v_id    bigint;
    v_count bigint;
BEGIN
    PERFORM tgsis.plain_write_check('tgsis', 'model_object');
    v_id := tgsis.model_id(p_name);
    INSERT INTO tgsis.model_object (geoid, modelid)
    SELECT o, v_id FROM unnest(tgsis.checked_objects(p_objects)) o
     WHERE NOT EXISTS (SELECT FROM tgsis.model_object mo WHERE mo.geoid = o AND mo.modelid = v_id);
    GET DIAGNOSTICS v_count = ROW_COUNT;
    RETURN v_count;
END
$$;

COMMENT ON FUNCTION tgsis.add_to_model(text, bigint[]) IS
    'add stored objects to the model called name in the session''s version (members stay members); returns the number added';

-- ==== modelsets/remove_from_model.sql ====
-- tgsis.remove_from_model(name, objects): take objects out of a model (the objects stay); returns how many left it.
CREATE FUNCTION tgsis.remove_from_model(p_name text, p_objects bigint[])
RETURNS bigint
LANGUAGE plpgsql
VOLATILE
SET search_path FROM CURRENT
AS $$
DECLARE
    v_id    bigint;
    v_count bigint;
BEGIN
    PERFORM tgsis.plain_write_check('tgsis', 'model_object');
    v_id := tgsis.model_id(p_name);
    DELETE FROM tgsis.model_object mo WHERE mo.modelid = v_id AND mo.geoid = ANY (p_objects);
    GET DIAGNOSTICS v_count = ROW_COUNT;
    RETURN v_count;
END
$$;

COMMENT ON FUNCTION tgsis.remove_from_model(text, bigint[]) IS
    'remove objects from the model called name in the session''s version (the objects themselves stay); returns the number removed';

-- ==== modelsets/model_objects.sql ====
-- tgsis.model_objects(name): the objects of a model in the session's version, with their feature class and name.
CREATE FUNCTION tgsis.model_objects(p_name text)
RETURNS TABLE (geoid bigint, classname text, geoname text)
LANGUAGE plpgsql
STABLE
SET search_path FROM CURRENT
AS $$
DECLARE
    v_id bigint := tgsis.model_id(p_name);
BEGIN
    RETURN QUERY
    SELECT mo.geoid, c.classname, g.geoname
      FROM tgsis.model_object mo
      JOIN tgsis.geometry g ON g.geoid = mo.geoid
      LEFT JOIN LATERAL (SELECT ct.classname FROM tgsis.catalog ct
                          WHERE ct.geotype = g.geotype AND ct.timemodel = g.timemodel
                            AND tgsis.feature_of_class(ct.classname, mo.geoid)
                          ORDER BY ct.classname LIMIT 1) c ON true
     WHERE mo.modelid = v_id
     ORDER BY mo.geoid;
END
$$;

COMMENT ON FUNCTION tgsis.model_objects(text) IS
    'the objects (geoid, their feature class, their name) of the model called name in the session''s version, by id';

-- ==== versioning/enable_feature_versioning.sql ====
-- tgsis.enable_feature_versioning(): version model 1 and every feature class as one object class, 'feature', keyed by geoid.
-- iudorder: the storage tables' own (tgsis.model_tables: geometry 0, vertices,
-- instants and periods 1, the rest 2), feature tables 3, property tables 4.
-- Classes registered later are versioned as they are created.
CREATE FUNCTION tgsis.enable_feature_versioning()
RETURNS integer
LANGUAGE plpgsql
VOLATILE
SECURITY DEFINER
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_table text;
    v_order integer;
    v_objectclass text;
    v_key   text;
    v_class text;
    v_count integer;
BEGIN
    SELECT count(*) INTO v_count FROM tgsis.versioned_tables
     WHERE objectclass = 'feature' OR (schemaname = 'tgsis' AND tablename IN (SELECT tablename FROM tgsis.model_tables));
    FOR v_class IN SELECT classname FROM tgsis.catalog ORDER BY classname LOOP
        PERFORM tgsis.version_class_tables(v_class);
    END LOOP;
    -- the storage of every data model (tgsis.model_tables), referenced rows first
    FOR v_table, v_order, v_objectclass, v_key IN
        SELECT tablename, iudorder, objectclass, keycolumn FROM tgsis.model_tables ORDER BY model, iudorder, tablename LOOP
        IF NOT EXISTS (SELECT FROM tgsis.versioned_tables WHERE schemaname = 'tgsis' AND tablename = v_table) THEN
            PERFORM tgsis.enable_versioning_rel(format('tgsis.%I', v_table)::regclass, v_key, v_objectclass, v_order);
        END IF;
    END LOOP;
    FOR v_class IN SELECT classname FROM tgsis.catalog ORDER BY classname LOOP
        PERFORM tgsis.create_class_view(v_class);
    END LOOP;
    RETURN (SELECT count(*) FROM tgsis.versioned_tables
             WHERE objectclass = 'feature' OR (schemaname = 'tgsis' AND tablename IN (SELECT tablename FROM tgsis.model_tables)))
           - v_count;
END
$$;

REVOKE ALL ON FUNCTION tgsis.enable_feature_versioning() FROM PUBLIC;

COMMENT ON FUNCTION tgsis.enable_feature_versioning() IS
    'version the storage tables of every data model (tgsis.model_tables: geometry, vrtx, simplices, the model-2 and model-3 tables, ...) and every feature class''s tables as object class ''feature'' (key geoid/_geoid); returns the number of tables newly versioned';

-- ==== versioning/disable_feature_versioning.sql ====
-- tgsis.disable_feature_versioning(force): make model 1 and the feature-class tables plain again with DEFAULT's rows.
CREATE FUNCTION tgsis.disable_feature_versioning(p_force boolean DEFAULT false)
RETURNS bigint
LANGUAGE plpgsql
VOLATILE
SECURITY DEFINER
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_t       tgsis.versioned_tables;
    v_class   text;
    v_removed bigint := 0;
BEGIN
    FOR v_class IN SELECT classname FROM tgsis.catalog LOOP
        EXECUTE format('DROP VIEW IF EXISTS %I.%I', (SELECT schemaname FROM tgsis.catalog WHERE classname = v_class),
                       (SELECT viewname FROM tgsis.catalog WHERE classname = v_class));
    END LOOP;
    FOR v_t IN SELECT * FROM tgsis.versioned_tables
                WHERE objectclass = 'feature' OR (schemaname = 'tgsis' AND tablename IN (SELECT tablename FROM tgsis.model_tables))
                ORDER BY iudorder DESC, tablename LOOP
        v_removed := v_removed + tgsis.disable_versioning_rel(format('%I.%I', v_t.schemaname, v_t.tablename)::regclass, p_force);
    END LOOP;
    FOR v_class IN SELECT classname FROM tgsis.catalog ORDER BY classname LOOP
        PERFORM tgsis.create_class_view(v_class);
    END LOOP;
    RETURN v_removed;
END
$$;

REVOKE ALL ON FUNCTION tgsis.disable_feature_versioning(boolean) FROM PUBLIC;

COMMENT ON FUNCTION tgsis.disable_feature_versioning(boolean) IS
    'make tgsis.geometry, vrtx, simplices and feature-class tables plain again with the rows DEFAULT sees (see disable_versioning); returns the row versions removed';

-- ==== model1/comparable_geometry.sql ====
-- tgsis.comparable_geometry(geoid, revisions, seen_in): the geotype of a geometry that mesh comparison can take, or a TG100/TG200 error.
-- Reads the geometry row as the session sees it (revisions NULL) or at a
-- revision set (from the versioned storage); seen_in ends the messages
-- (e.g. ' in version ''edit''').
CREATE FUNCTION tgsis.comparable_geometry(p_geoid bigint, p_revisions integer[], p_seen_in text DEFAULT '')
RETURNS text
LANGUAGE plpgsql
STABLE
AS $$
DECLARE
    v_geo record;
BEGIN
    IF p_geoid IS NULL THEN
        RAISE EXCEPTION 'a geometry id is required, got NULL' USING ERRCODE = 'TG100';
    END IF;
    IF p_revisions IS NULL THEN
        SELECT g.geotype, g.timemodel INTO v_geo FROM tgsis.geometry g WHERE g.geoid = p_geoid;
    ELSE
        SELECT g.geotype, g.timemodel INTO v_geo FROM tgsis.geometry_ver g
         WHERE g.geoid = p_geoid AND (g.revision = ANY (p_revisions)) IS TRUE
           AND (NOT g.revclosed OR NOT (g.lastrevs && p_revisions));
    END IF;
    IF NOT FOUND THEN
        RAISE EXCEPTION 'geometry % does not exist%', p_geoid, p_seen_in
            USING ERRCODE = 'TG200', HINT = 'SELECT geoid, geotype FROM tgsis.geometry lists the stored geometries';
    END IF;
    IF v_geo.geotype = 'GEOMETRYCOLLECTION' THEN
        RAISE EXCEPTION 'geometry % is a GEOMETRYCOLLECTION%: collections are not compared as one mesh', p_geoid, p_seen_in
            USING ERRCODE = 'TG100',
                  HINT = format('compare its members one by one: SELECT geoids FROM tgsis.geometry WHERE geoid = %s', p_geoid);
    END IF;
    IF v_geo.timemodel <> 'STATIC' THEN
        RAISE EXCEPTION 'geometry % is a temporal surface (time model %)%: only static geometries (model 1) are compared',
                        p_geoid, v_geo.timemodel, p_seen_in
            USING ERRCODE = 'TG100',
                  DETAIL = 'Its shape is in the tables of models 2 and 3, one per instant, not in tgsis.vrtx and tgsis.trgl.';
    END IF;
    RETURN v_geo.geotype;
END
$$;

COMMENT ON FUNCTION tgsis.comparable_geometry(bigint, integer[], text) IS
    'geotype of a geometry (as the session sees it, or at a revision set) that mesh comparison takes; TG200 if it does not exist, TG100 for NULL, a GEOMETRYCOLLECTION or a temporal surface';

-- ==== model1/mesh_changes.sql ====
-- tgsis.mesh_changes(old_geoid, old_revisions, new_geoid, new_revisions, old_seen_in, new_seen_in): every vertex and cell of two meshes, kept, removed or added.
-- The comparison core behind tgsis.geometry_changes and
-- tgsis.geometry_version_changes, with the definitions of
-- tgsis.compare_meshes in the Python client (../shared/spec/mesh-comparison.md):
--   * a new vertex is kept when an old vertex has numerically equal x, y, z
--     (float8 equality: -0.0 = 0.0, one ulp apart differs); the pairing is
--     one-to-one: when a coordinate triple repeats on one side, the k-th
--     old vertex with it (in vrtxid order) pairs with the k-th new one;
--   * a new cell is kept when all its vertices are kept and an old cell has
--     the corresponding old vertices in an even permutation of its order
--     (for segments the same direction; a reversed triangle is not kept),
--     paired one-to-one the same way (in cell id order);
--   * all other old rows are removed, all other new rows added.
-- A side is a geometry read as the session sees it (revisions NULL) or,
-- with a revision set, from the versioned storage with the predicate of
-- tgsis.rows_at, restricted to the geometry's rows by the index (rows_at
-- itself would return every geometry's rows). Both must exist and be
-- static geometries of one geotype other than GEOMETRYCOLLECTION
-- (tgsis.comparable_geometry; seen_in ends its messages).
--
-- Set-based: a hash full join on (x, y, z) pairs the vertices; the new
-- cells are renamed to old vertex ids through the pairs (one hash join per
-- cell corner); a hash full join on (sorted vertex ids, permutation parity)
-- pairs the cells. Those joins are one-to-one exactly when no row is in
-- two pairs, which counts of each side tell; only then (the normal case)
-- are their results used, otherwise the rows are ranked within equal
-- coordinates (or equal cell keys) and joined on the rank too. The ranking
-- branches stand behind one-time filters, so a normal mesh sorts nothing.
CREATE FUNCTION tgsis.mesh_changes(
    p_old_geoid     bigint,
    p_old_revisions integer[],
    p_new_geoid     bigint,
    p_new_revisions integer[],
    p_old_seen_in   text DEFAULT '',
    p_new_seen_in   text DEFAULT '')
RETURNS TABLE (element text, status text, old_id bigint, new_id bigint)
LANGUAGE plpgsql
STABLE
AS $$
DECLARE
    v_old_type text;
    v_new_type text;
    v_table  text;
    v_cellid text;
    v_k      integer;
    v_vrtx   text[];
    v_cells  text[];
    v_filter text;
    v_set    integer[];
    v_key    text;
    v_old    text;
    v_new    text;
    v_cols   text;
    v_keycols text[];
    v_side   integer;
BEGIN
    IF (p_old_revisions IS NOT NULL OR p_new_revisions IS NOT NULL)
       AND (SELECT count(*) FROM tgsis.versioned_tables t
             WHERE t.schemaname = 'tgsis' AND t.tablename IN ('geometry', 'vrtx', 'point', 'segment', 'trgl', 'tetra')) < 6 THEN
        RAISE EXCEPTION 'model 1 is not versioned: there are no versions or revisions of geometry % to compare',
                        coalesce(p_old_geoid::text, 'NULL')
            USING ERRCODE = 'TG100',
                  HINT = 'SELECT tgsis.enable_feature_versioning() versions model 1 and every feature class; tgsis.compare_geometries compares two geometries';
    END IF;
    v_old_type := tgsis.comparable_geometry(p_old_geoid, p_old_revisions, p_old_seen_in);
    v_new_type := tgsis.comparable_geometry(p_new_geoid, p_new_revisions, p_new_seen_in);
    IF v_old_type <> v_new_type THEN
        RAISE EXCEPTION 'cannot compare geometry % (%) with geometry % (%): the geotypes differ',
                        p_old_geoid || p_old_seen_in, v_old_type, p_new_geoid || p_new_seen_in, v_new_type
            USING ERRCODE = 'TG100', HINT = 'compare geometries of one geotype: points, lines, surfaces or tetrahedra';
    END IF;
    v_table := tgsis.simplex_table(v_old_type);
    v_cellid := CASE v_table WHEN 'point' THEN 'pointid' WHEN 'segment' THEN 'segid' WHEN 'trgl' THEN 'trglid'
                             ELSE 'tetraid' END;
    v_k := CASE v_table WHEN 'point' THEN 1 WHEN 'segment' THEN 2 WHEN 'trgl' THEN 3 ELSE 4 END;
    v_keycols := ARRAY(SELECT 's' || i FROM generate_series(1, v_k) AS i) || 'odd'::text;
    -- the rows of each side: parameters $1, $2 (old geoid, revision set) and $3, $4 (new)
    v_cols := (SELECT string_agg(format('v.vrtxid%s', i), ', ') FROM generate_series(1, v_k) AS i);
    FOR v_side IN 1 .. 2 LOOP
        v_set := CASE v_side WHEN 1 THEN p_old_revisions ELSE p_new_revisions END;
        v_filter := CASE WHEN v_set IS NULL THEN format('v.geoid = $%s', 2 * v_side - 1)
                         ELSE format('v.geoid = $%s AND (v.revision = ANY ($%s)) IS TRUE '
                                     'AND (NOT v.revclosed OR NOT (v.lastrevs && $%2$s))', 2 * v_side - 1, 2 * v_side) END;
        v_vrtx[v_side] := format('SELECT v.vrtxid AS id, v.x, v.y, v.z FROM %s v WHERE %s',
                                 CASE WHEN v_set IS NULL THEN 'tgsis.vrtx' ELSE 'tgsis.vrtx_ver' END, v_filter);
        v_cells[v_side] := format('SELECT v.%I AS id, %s FROM tgsis.%I v WHERE %s', v_cellid, v_cols,
                                  CASE WHEN v_set IS NULL THEN v_table ELSE v_table || '_ver' END, v_filter);
    END LOOP;

    -- a cell's key: its vertex ids ascending (least/greatest sorting networks) and whether its
    -- order is an odd permutation of them (parity of the number of inversions); %5$s and %6$s
    -- wrap s1, which for a new cell with a vertex that is not kept is NULL, so that it matches nothing
    v_key := CASE v_k
        WHEN 1 THEN '%5$s%1$s%6$s AS s1, false AS odd'
        WHEN 2 THEN '%5$sleast(%1$s, %2$s)%6$s AS s1, greatest(%1$s, %2$s) AS s2, %1$s > %2$s AS odd'
        WHEN 3 THEN '%5$sleast(%1$s, %2$s, %3$s)%6$s AS s1, '
                    'greatest(least(%1$s, %2$s), least(greatest(%1$s, %2$s), %3$s)) AS s2, '
                    'greatest(%1$s, %2$s, %3$s) AS s3, '
                    '((%1$s > %2$s) <> (%1$s > %3$s)) <> (%2$s > %3$s) AS odd'
        ELSE '%5$sleast(%1$s, %2$s, %3$s, %4$s)%6$s AS s1, '
             'least(greatest(least(%1$s, %2$s), least(%3$s, %4$s)), least(greatest(%1$s, %2$s), greatest(%3$s, %4$s))) AS s2, '
             'greatest(greatest(least(%1$s, %2$s), least(%3$s, %4$s)), least(greatest(%1$s, %2$s), greatest(%3$s, %4$s))) AS s3, '
             'greatest(%1$s, %2$s, %3$s, %4$s) AS s4, '
             '((((((%1$s > %2$s) <> (%1$s > %3$s)) <> (%1$s > %4$s)) <> (%2$s > %3$s)) <> (%2$s > %4$s)) <> (%3$s > %4$s)) AS odd'
    END;
    v_old := format(v_key, 'c.vrtxid1', 'c.vrtxid2', 'c.vrtxid3', 'c.vrtxid4', '', '');
    v_new := format(v_key, 'm1.o', 'm2.o', 'm3.o', 'm4.o',
                    format('CASE WHEN %s THEN ',
                           (SELECT string_agg(format('m%s.o IS NOT NULL', i), ' AND ') FROM generate_series(1, v_k) AS i)),
                    ' END');

    RETURN QUERY EXECUTE format($q$
        WITH ov AS NOT MATERIALIZED (%1$s),
             nv AS NOT MATERIALIZED (%2$s),
             -- vertex pairs by equal coordinates, and the vertices of either side without one
             fv AS MATERIALIZED (
                 SELECT ov.id AS o, nv.id AS n FROM ov FULL JOIN nv ON nv.x = ov.x AND nv.y = ov.y AND nv.z = ov.z),
             -- one-to-one unless a coordinate triple repeats on one side (then a row occurs in several pairs)
             vok AS MATERIALIZED (
                 SELECT count(fv.o) = (SELECT count(*) FROM ov) AND count(fv.n) = (SELECT count(*) FROM nv) AS ok FROM fv),
             vm AS MATERIALIZED (
                 SELECT fv.o, fv.n FROM fv WHERE fv.o IS NOT NULL AND fv.n IS NOT NULL AND (SELECT ok FROM vok)
                 UNION ALL
                 SELECT a.id, b.id
                   FROM (SELECT ov.*, row_number() OVER (PARTITION BY ov.x, ov.y, ov.z ORDER BY ov.id) AS r FROM ov) a
                   JOIN (SELECT nv.*, row_number() OVER (PARTITION BY nv.x, nv.y, nv.z ORDER BY nv.id) AS r FROM nv) b
                     ON b.x = a.x AND b.y = a.y AND b.z = a.z AND b.r = a.r
                  WHERE NOT (SELECT ok FROM vok)),
             oc0 AS NOT MATERIALIZED (%3$s),
             nc0 AS NOT MATERIALIZED (%4$s),
             oc AS NOT MATERIALIZED (SELECT c.id, %5$s FROM oc0 c),
             nc AS NOT MATERIALIZED (SELECT c.id, %6$s FROM nc0 c %7$s),
             -- cell pairs by equal keys, and the cells of either side without one
             fc AS MATERIALIZED (SELECT oc.id AS o, nc.id AS n FROM oc FULL JOIN nc ON %8$s),
             cok AS MATERIALIZED (
                 SELECT count(fc.o) = (SELECT count(*) FROM oc0) AND count(fc.n) = (SELECT count(*) FROM nc0) AS ok FROM fc),
             cm AS NOT MATERIALIZED (
                 SELECT fc.o, fc.n FROM fc WHERE fc.o IS NOT NULL AND fc.n IS NOT NULL AND (SELECT ok FROM cok)
                 UNION ALL
                 SELECT a.id, b.id
                   FROM (SELECT oc.*, row_number() OVER (PARTITION BY %9$s ORDER BY oc.id) AS r FROM oc) a
                   JOIN (SELECT nc.*, row_number() OVER (PARTITION BY %10$s ORDER BY nc.id) AS r FROM nc
                          WHERE nc.s1 IS NOT NULL) b
                     ON %11$s AND b.r = a.r
                  WHERE NOT (SELECT ok FROM cok))
        SELECT 'vertex', 'kept', vm.o, vm.n FROM vm
        UNION ALL
        SELECT 'vertex', 'removed', fv.o, NULL FROM fv WHERE fv.n IS NULL AND (SELECT ok FROM vok)
        UNION ALL
        SELECT 'vertex', 'removed', ov.id, NULL FROM ov
         WHERE NOT (SELECT ok FROM vok) AND NOT EXISTS (SELECT FROM vm WHERE vm.o = ov.id)
        UNION ALL
        SELECT 'vertex', 'added', NULL, fv.n FROM fv WHERE fv.o IS NULL AND (SELECT ok FROM vok)
        UNION ALL
        SELECT 'vertex', 'added', NULL, nv.id FROM nv
         WHERE NOT (SELECT ok FROM vok) AND NOT EXISTS (SELECT FROM vm WHERE vm.n = nv.id)
        UNION ALL
        SELECT 'cell', 'kept', cm.o, cm.n FROM cm
        UNION ALL
        SELECT 'cell', 'removed', fc.o, NULL FROM fc WHERE fc.n IS NULL AND (SELECT ok FROM cok)
        UNION ALL
        SELECT 'cell', 'removed', oc0.id, NULL FROM oc0
         WHERE NOT (SELECT ok FROM cok) AND NOT EXISTS (SELECT FROM cm WHERE cm.o = oc0.id)
        UNION ALL
        SELECT 'cell', 'added', NULL, fc.n FROM fc WHERE fc.o IS NULL AND (SELECT ok FROM cok)
        UNION ALL
        SELECT 'cell', 'added', NULL, nc0.id FROM nc0
         WHERE NOT (SELECT ok FROM cok) AND NOT EXISTS (SELECT FROM cm WHERE cm.n = nc0.id)
        $q$,
        v_vrtx[1], v_vrtx[2], v_cells[1], v_cells[2], v_old, v_new,
        (SELECT string_agg(format('LEFT JOIN vm m%1$s ON m%1$s.n = c.vrtxid%1$s', i), ' ') FROM generate_series(1, v_k) AS i),
        (SELECT string_agg(format('nc.%1$s = oc.%1$s', c), ' AND ') FROM unnest(v_keycols) AS c),
        (SELECT string_agg(format('oc.%s', c), ', ') FROM unnest(v_keycols) AS c),
        (SELECT string_agg(format('nc.%s', c), ', ') FROM unnest(v_keycols) AS c),
        (SELECT string_agg(format('b.%1$s = a.%1$s', c), ' AND ') FROM unnest(v_keycols) AS c))
      USING p_old_geoid, p_old_revisions, p_new_geoid, p_new_revisions;
END
$$;

COMMENT ON FUNCTION tgsis.mesh_changes(bigint, integer[], bigint, integer[], text, text) IS
    'comparison core of tgsis.geometry_changes and tgsis.geometry_version_changes: every vertex and cell of an old and a new static geometry of one geotype, each read in the session''s version (revisions NULL) or at a revision set, as (element vertex|cell, status kept|removed|added, old id, new id)';

-- ==== model1/geometry_changes.sql ====
-- tgsis.geometry_changes(old, new): one row per vertex and cell of two stored geometries: kept (with both ids), removed (old id) or added (new id).
-- Both are read as the session sees them (its version), must exist and be
-- static geometries of one geotype other than GEOMETRYCOLLECTION. The
-- definitions are those of tgsis.mesh_changes (and of tgsis.compare_meshes
-- in the Python client); tgsis.compare_geometries counts the same rows.
-- The kept vertices are the vertex matches: old_id and new_id of each pair.
CREATE FUNCTION tgsis.geometry_changes(p_old bigint, p_new bigint)
RETURNS TABLE (element text, status text, old_id bigint, new_id bigint)
LANGUAGE sql
STABLE
AS $$
    SELECT * FROM tgsis.mesh_changes(p_old, NULL, p_new, NULL)
$$;

COMMENT ON FUNCTION tgsis.geometry_changes(bigint, bigint) IS
    'every vertex and cell (point, segment, triangle, tetrahedron) of two static geometries of one geotype, in the session''s version: element vertex|cell, status kept (old_id and new_id), removed (old_id) or added (new_id); vertices are kept by equal coordinates, cells by kept vertices in the same orientation';

-- ==== model1/compare_geometries.sql ====
-- tgsis.compare_geometries(old, new): how many vertices and cells of two stored geometries were kept, removed and added, with the ids of the removed and added ones.
-- Six rows, always in this order: vertex kept, removed, added; cell kept,
-- removed, added. ids: the old ids of removed rows, the new ids of added
-- ones (ascending; '{}' when none), NULL for kept rows (the pairs can be
-- millions: tgsis.geometry_changes lists them).
CREATE FUNCTION tgsis.compare_geometries(p_old bigint, p_new bigint)
RETURNS TABLE (element text, status text, count bigint, ids bigint[])
LANGUAGE sql
STABLE
AS $$
    WITH c AS (
        SELECT c.element, c.status, count(*) AS n,
               array_agg(coalesce(c.old_id, c.new_id)) FILTER (WHERE c.status <> 'kept') AS ids
          FROM tgsis.geometry_changes(p_old, p_new) c
         GROUP BY c.element, c.status)
    SELECT f.element, f.status, coalesce(c.n, 0),
           CASE WHEN f.status <> 'kept' THEN ARRAY(SELECT i FROM unnest(c.ids) AS i ORDER BY i) END
      FROM (VALUES (1, 'vertex', 'kept'), (2, 'vertex', 'removed'), (3, 'vertex', 'added'),
                   (4, 'cell', 'kept'), (5, 'cell', 'removed'), (6, 'cell', 'added')) AS f(o, element, status)
      LEFT JOIN c ON c.element = f.element AND c.status = f.status
     ORDER BY f.o
$$;

COMMENT ON FUNCTION tgsis.compare_geometries(bigint, bigint) IS
    'what changed from one static geometry to another of its geotype, in the session''s version: six rows (vertex|cell, kept|removed|added) with the count and the ids (old ids removed, new ids added, ascending; NULL for kept); see tgsis.geometry_changes for the rows themselves';

-- ==== model1/geometry_version_changes.sql ====
-- tgsis.geometry_version_changes(geoid, old_version, new_version, old_revision, new_revision): tgsis.geometry_changes of one geometry between two versions or revisions.
-- Each side is the geometry as a version sees it at a revision (NULL: its
-- working revision), read without moving the session, as tgsis.rows_at
-- reads; needs model 1 versioned (tgsis.enable_feature_versioning). The
-- geometry must exist on both sides, as a static geometry of one geotype.
CREATE FUNCTION tgsis.geometry_version_changes(
    p_geoid        bigint,
    p_old_version  text,
    p_new_version  text,
    p_old_revision integer DEFAULT NULL,
    p_new_revision integer DEFAULT NULL)
RETURNS TABLE (element text, status text, old_id bigint, new_id bigint)
LANGUAGE sql
STABLE
AS $$
    SELECT *
      FROM tgsis.mesh_changes(p_geoid, tgsis.revision_set(tgsis.version_id(p_old_version), p_old_revision),
                              p_geoid, tgsis.revision_set(tgsis.version_id(p_new_version), p_new_revision),
                              format(' in version %L%s', p_old_version, ' at revision ' || p_old_revision),
                              format(' in version %L%s', p_new_version, ' at revision ' || p_new_revision))
$$;

COMMENT ON FUNCTION tgsis.geometry_version_changes(bigint, text, text, integer, integer) IS
    'every vertex and cell of a static geometry as one version (at a revision; NULL: its working revision) and as another sees it, without moving the session: element vertex|cell, status kept (old_id and new_id), removed (old_id) or added (new_id); needs model 1 versioned';

-- ==== model1/compare_geometry_versions.sql ====
-- tgsis.compare_geometry_versions(geoid, old_version, new_version, old_revision, new_revision): tgsis.compare_geometries of one geometry between two versions or revisions.
-- The same six rows, counted over tgsis.geometry_version_changes.
CREATE FUNCTION tgsis.compare_geometry_versions(
    p_geoid        bigint,
    p_old_version  text,
    p_new_version  text,
    p_old_revision integer DEFAULT NULL,
    p_new_revision integer DEFAULT NULL)
RETURNS TABLE (element text, status text, count bigint, ids bigint[])
LANGUAGE sql
STABLE
AS $$
    WITH c AS (
        SELECT c.element, c.status, count(*) AS n,
               array_agg(coalesce(c.old_id, c.new_id)) FILTER (WHERE c.status <> 'kept') AS ids
          FROM tgsis.geometry_version_changes(p_geoid, p_old_version, p_new_version, p_old_revision, p_new_revision) c
         GROUP BY c.element, c.status)
    SELECT f.element, f.status, coalesce(c.n, 0),
           CASE WHEN f.status <> 'kept' THEN ARRAY(SELECT i FROM unnest(c.ids) AS i ORDER BY i) END
      FROM (VALUES (1, 'vertex', 'kept'), (2, 'vertex', 'removed'), (3, 'vertex', 'added'),
                   (4, 'cell', 'kept'), (5, 'cell', 'removed'), (6, 'cell', 'added')) AS f(o, element, status)
      LEFT JOIN c ON c.element = f.element AND c.status = f.status
     ORDER BY f.o
$$;

COMMENT ON FUNCTION tgsis.compare_geometry_versions(bigint, text, text, integer, integer) IS
    'what changed in a static geometry from one version (at a revision; NULL: its working revision) to another, without moving the session: six rows (vertex|cell, kept|removed|added) with the count and the ids (old ids removed, new ids added, ascending; NULL for kept)';

-- ==== temporal/checked_time.sql ====
-- tgsis.checked_time(t): t itself, or TG100 when it is NaN (no instant compares with it).
CREATE FUNCTION tgsis.checked_time(p_t double precision)
RETURNS double precision
LANGUAGE plpgsql
IMMUTABLE
PARALLEL SAFE
AS $$
BEGIN
    IF p_t = 'NaN' THEN
        RAISE EXCEPTION 'model time NaN is not a time'
            USING ERRCODE = 'TG100', HINT = 'give a number; -Infinity and Infinity mean before and after every instant';
    END IF;
    RETURN p_t;
END
$$;

COMMENT ON FUNCTION tgsis.checked_time(double precision) IS 'the model time given, or TG100 if it is NaN';

-- ==== temporal/checked_convention.sql ====
-- tgsis.checked_convention(convention): 'left' or 'right' (lower-cased), or TG100 naming the bad value.
CREATE FUNCTION tgsis.checked_convention(p_convention text)
RETURNS text
LANGUAGE plpgsql
IMMUTABLE
PARALLEL SAFE
AS $$
BEGIN
    IF lower(p_convention) IN ('left', 'right') THEN
        RETURN lower(p_convention);
    END IF;
    RAISE EXCEPTION 'step convention % must be left or right', coalesce(quote_literal(p_convention), 'NULL')
        USING ERRCODE = 'TG100',
              DETAIL = 'left-closed: G(t) = G_i for t_i <= t < t_i+1; right-closed: G(t) = G_i for t_i-1 < t <= t_i.';
END
$$;

COMMENT ON FUNCTION tgsis.checked_convention(text) IS
    'the step convention of model-2 queries, ''left'' (left-closed) or ''right'' (right-closed); TG100 otherwise';

-- ==== temporal/instant_at.sql ====
-- tgsis.instant_at(geoid, t, convention): the instant of a model-2 surface whose shape it has at t, or NULL (none then).
-- left-closed: the last instant <= t; right-closed: the first instant >= t.
-- Before the first instant: NULL; after the last: the last if the geometry
-- is alive, else NULL.
CREATE FUNCTION tgsis.instant_at(p_geoid bigint, p_t double precision, p_convention text DEFAULT 'left')
RETURNS double precision
LANGUAGE sql
STABLE
PARALLEL SAFE
AS $$
    SELECT CASE
               WHEN tgsis.checked_time(p_t) < s.first THEN NULL
               WHEN p_t > s.last THEN CASE WHEN g.alive THEN s.last END
               WHEN lower(p_convention) = 'left'
                   THEN (SELECT max(i.times) FROM tgsis.times i WHERE i.geoid = p_geoid AND i.times <= p_t)
               ELSE (SELECT min(i.times) FROM tgsis.times i WHERE i.geoid = p_geoid AND i.times >= p_t)
           END
      FROM tgsis.geometry g,
           LATERAL (SELECT min(i.times) AS first, max(i.times) AS last FROM tgsis.times i WHERE i.geoid = p_geoid) s
     WHERE g.geoid = p_geoid AND g.timemodel = 'INSTANTS'
       -- a one-time filter, checked whatever t: a bad convention is an error, not an empty answer
       AND tgsis.checked_convention(p_convention) IS NOT NULL
$$;

COMMENT ON FUNCTION tgsis.instant_at(bigint, double precision, text) IS
    'model 2: the instant whose surface holds at t under the left- or right-closed step convention; NULL before the first instant, and after the last unless the geometry is alive';

-- ==== temporal/evolving_frame.sql ====
-- tgsis.evolving_frame(geoid, t): where t falls in a model-3 surface: its topology period, the bracketing geometry instants t0 <= t <= t1 and the weight w = (t - t0) / (t1 - t0).
-- The period is the last topology instant <= t (at a topology change the new
-- topology applies). No row before the first instant, nor after the last
-- geometry instant unless the geometry is alive (then t0 = t1 = the last, w = 0).
CREATE FUNCTION tgsis.evolving_frame(p_geoid bigint, p_t double precision)
RETURNS TABLE (timem double precision, t0 double precision, t1 double precision, w double precision)
LANGUAGE sql
STABLE
PARALLEL SAFE
AS $$
    WITH period AS (
        SELECT m.timem,
               NOT EXISTS (SELECT FROM tgsis.timem n WHERE n.geoid = p_geoid AND n.timem > m.timem) AS last
          FROM tgsis.timem m
         WHERE m.geoid = p_geoid AND m.timem <= tgsis.checked_time(p_t)
         ORDER BY m.timem DESC
         LIMIT 1
    ), bracket AS (
        SELECT p.timem, p.last,
               (SELECT max(i.timet) FROM tgsis.timet i WHERE i.geoid = p_geoid AND i.timem = p.timem AND i.timet <= p_t) AS lo,
               (SELECT min(i.timet) FROM tgsis.timet i WHERE i.geoid = p_geoid AND i.timem = p.timem AND i.timet >= p_t) AS hi
          FROM period p
    )
    SELECT b.timem, b.lo, coalesce(b.hi, b.lo),
           CASE WHEN b.hi IS NULL OR b.hi = b.lo THEN 0 ELSE (p_t - b.lo) / (b.hi - b.lo) END
      FROM bracket b
      JOIN tgsis.geometry g ON g.geoid = p_geoid AND g.timemodel = 'EVOLVING'
     WHERE b.lo IS NOT NULL
       AND (b.hi IS NOT NULL OR g.alive OR NOT b.last)
$$;

COMMENT ON FUNCTION tgsis.evolving_frame(bigint, double precision) IS
    'model 3: topology period (timem) and bracketing geometry instants t0 <= t <= t1 of an evolving surface at t, with w = (t - t0)/(t1 - t0); no row when the surface does not exist at t';

-- ==== temporal/vertices_at.sql ====
-- tgsis.vertices_at(geoid, t, convention): the vertices of a surface at model time t (ids as stored; any order).
-- Model 3: nodes of the period containing t, each moved linearly between the
-- bracketing geometry instants, x(t) = x0 + w (x1 - x0); at a geometry
-- instant exactly, the stored positions (one index scan, no join). Model 2:
-- the vertices of the instant tgsis.instant_at chooses. Static geometries:
-- their vertices at every t. One set-based query, inlined into the caller.
--
-- The frame is read through scalar subqueries (InitPlans), not joined: their
-- values are constants to the planner, so each side of the join is an index
-- scan of (geoid, timem, timet) that returns one instant's nodes in nodeid
-- order, and the two sides merge-join (or hash-join) on nodeid. Joined to the
-- frame instead, the planner could not bound d4dvrtx by the instants: it
-- scanned every row of the table (all instants, all surfaces) into a hash
-- join (see docs/performance.md).
CREATE FUNCTION tgsis.vertices_at(p_geoid bigint, p_t double precision, p_convention text DEFAULT 'left')
RETURNS TABLE (vrtxid bigint, x double precision, y double precision, z double precision)
LANGUAGE sql
STABLE
PARALLEL SAFE
AS $$
    WITH f AS MATERIALIZED (SELECT * FROM tgsis.evolving_frame(p_geoid, p_t))
    SELECT a.nodeid, a.x + (SELECT f.w FROM f) * (b.x - a.x), a.y + (SELECT f.w FROM f) * (b.y - a.y),
           a.z + (SELECT f.w FROM f) * (b.z - a.z)
      FROM tgsis.d4dvrtx a
      JOIN tgsis.d4dvrtx b ON b.nodeid = a.nodeid
     WHERE a.geoid = p_geoid AND a.timem = (SELECT f.timem FROM f) AND a.timet = (SELECT f.t0 FROM f)
       AND b.geoid = p_geoid AND b.timem = (SELECT f.timem FROM f) AND b.timet = (SELECT f.t1 FROM f)
       AND (SELECT f.t0 < f.t1 FROM f)
       AND tgsis.checked_convention(p_convention) IS NOT NULL  -- model 3 has no steps, but a bad value is an error
    UNION ALL
    SELECT a.nodeid, a.x, a.y, a.z
      FROM tgsis.d4dvrtx a
     WHERE a.geoid = p_geoid AND a.timem = (SELECT f.timem FROM f) AND a.timet = (SELECT f.t0 FROM f)
       AND (SELECT f.t0 = f.t1 FROM f)
       AND tgsis.checked_convention(p_convention) IS NOT NULL
    UNION ALL
    SELECT v.vrtxid, v.x, v.y, v.z
      FROM tgsis.times_vrtx v
     WHERE v.geoid = p_geoid AND v.times = tgsis.instant_at(p_geoid, p_t, p_convention)
    UNION ALL
    SELECT v.vrtxid, v.x, v.y, v.z
      FROM tgsis.vrtx v
     WHERE v.geoid = p_geoid
       AND EXISTS (SELECT FROM tgsis.geometry g WHERE g.geoid = p_geoid AND g.timemodel = 'STATIC')
       AND tgsis.checked_convention(p_convention) IS NOT NULL
$$;

COMMENT ON FUNCTION tgsis.vertices_at(bigint, double precision, text) IS
    'vertices (vrtxid, x, y, z) of a geometry at model time t: model 3 interpolated linearly in the period containing t, model 2 by the left- or right-closed step convention, static ones always; empty when the object does not exist at t';

-- ==== temporal/property_at.sql ====
-- tgsis.property_at(class, geoid, property, t, convention): the values of a numeric vertex or cell property of a feature at model time t.
-- What the snapshot at t (tgsis.vertices_at, tgsis.triangles_at) leaves out:
-- the property values that go with it, one row per vertex or node (VERTEX
-- classes) or triangle (CELL), idx as in the snapshot. Model 3: linear
-- between the bracketing geometry instants of the period containing t,
-- a + w (b - a), the formula EvolvingSurface.at uses (equal to the bit);
-- model 2: the values of the instant the step convention chooses; static:
-- the stored values at every t. No rows when the feature does not exist at
-- t; NULL values stay NULL.
CREATE FUNCTION tgsis.property_at(p_class text, p_geoid bigint, p_property text, p_t double precision,
                                  p_convention text DEFAULT 'left')
RETURNS TABLE (idx bigint, value double precision)
LANGUAGE plpgsql
STABLE
AS $$
DECLARE
    v_class tgsis.catalog := tgsis.catalog_row(p_class);
BEGIN
    IF v_class.timemodel = 'STATIC' THEN
        -- the question's checks (a numeric vertex or cell property, the feature one of the class) for a static class
        -- (a scalar property of the class's own alignment: the others live in otherprotable, vectors have sizes)
        IF NOT EXISTS (SELECT FROM jsonb_array_elements(v_class.cell_properties) p
                        WHERE p ->> 'name' = p_property AND NOT p ? 'size' AND NOT p ? 'alignment'
                          AND p ->> 'type' IN ('smallint', 'integer', 'bigint', 'real', 'double precision', 'numeric')) THEN
            RAISE EXCEPTION 'feature class % has no numeric scalar % property %', p_class, lower(v_class.proalignment),
                    coalesce(quote_literal(p_property), 'NULL')
                USING ERRCODE = 'TG103',
                      HINT = format('its %s properties: %s', lower(v_class.proalignment),
                                    coalesce((SELECT string_agg(p ->> 'name', ', ') FROM jsonb_array_elements(v_class.cell_properties) p),
                                             'none'));
        END IF;
        PERFORM tgsis.checked_time(p_t), tgsis.checked_convention(p_convention);
        RETURN QUERY EXECUTE format('SELECT p._idx, p.%I::double precision FROM %I.%I p WHERE p._geoid = $1 ORDER BY p._idx',
                                    p_property, v_class.schemaname, v_class.cellprotable) USING p_geoid;
        RETURN;
    END IF;
    PERFORM tgsis.checked_question(p_class, p_geoid, p_property, true, '=', 0, p_convention);
    PERFORM tgsis.checked_time(p_t);
    IF v_class.timemodel = 'INSTANTS' THEN
        RETURN QUERY EXECUTE format(
            'SELECT p._idx, p.%I::double precision FROM %I.%I p
              WHERE p._geoid = $1 AND p._times = tgsis.instant_at($1, $2, $3) ORDER BY p._idx',
            p_property, v_class.schemaname, v_class.cellprotable) USING p_geoid, p_t, p_convention;
    ELSE
        RETURN QUERY EXECUTE format(
            'WITH f AS MATERIALIZED (SELECT * FROM tgsis.evolving_frame($1, $2))
             SELECT a._idx, CASE WHEN (SELECT f.t0 = f.t1 FROM f) THEN a.%1$I::double precision
                                 ELSE a.%1$I::double precision
                                      + (SELECT f.w FROM f) * (b.%1$I::double precision - a.%1$I::double precision) END
               FROM %2$I.%3$I a
               JOIN %2$I.%3$I b ON b._geoid = a._geoid AND b._timem = a._timem AND b._idx = a._idx
              WHERE a._geoid = $1 AND a._timem = (SELECT f.timem FROM f) AND a._timet = (SELECT f.t0 FROM f)
                AND b._timet = (SELECT f.t1 FROM f)
              ORDER BY a._idx',
            p_property, v_class.schemaname, v_class.cellprotable) USING p_geoid, p_t;
    END IF;
END
$$;

COMMENT ON FUNCTION tgsis.property_at(text, bigint, text, double precision, text) IS
    'values (idx, value) of a numeric vertex or cell property of a feature at model time t: model 3 interpolated as the snapshot is, model 2 by the step convention, static ones always; none when the feature does not exist at t';

-- ==== temporal/triangles_at.sql ====
-- tgsis.triangles_at(geoid, t, convention): the triangles of a surface at model time t, pointing at the vrtxid of tgsis.vertices_at.
-- The period comes from a scalar subquery (a constant to the planner, as in
-- tgsis.vertices_at): an index scan of that period, not a scan of every period.
CREATE FUNCTION tgsis.triangles_at(p_geoid bigint, p_t double precision, p_convention text DEFAULT 'left')
RETURNS TABLE (trglid bigint, vrtxid1 bigint, vrtxid2 bigint, vrtxid3 bigint)
LANGUAGE sql
STABLE
PARALLEL SAFE
AS $$
    SELECT c.trglid, c.nodeid1, c.nodeid2, c.nodeid3
      FROM tgsis.d4dtrgl c
     WHERE c.geoid = p_geoid AND c.timem = (SELECT f.timem FROM tgsis.evolving_frame(p_geoid, p_t) f)
       AND tgsis.checked_convention(p_convention) IS NOT NULL  -- model 3 has no steps, but a bad value is an error
    UNION ALL
    SELECT c.trglid, c.vrtxid1, c.vrtxid2, c.vrtxid3
      FROM tgsis.times_trgl c
     WHERE c.geoid = p_geoid AND c.times = tgsis.instant_at(p_geoid, p_t, p_convention)
    UNION ALL
    SELECT c.trglid, c.vrtxid1, c.vrtxid2, c.vrtxid3
      FROM tgsis.trgl c
     WHERE c.geoid = p_geoid
       AND EXISTS (SELECT FROM tgsis.geometry g WHERE g.geoid = p_geoid AND g.timemodel = 'STATIC')
       AND tgsis.checked_convention(p_convention) IS NOT NULL
$$;

COMMENT ON FUNCTION tgsis.triangles_at(bigint, double precision, text) IS
    'triangles (trglid, vrtxid1..3) of a surface at model time t, with the period (model 3) or instant (model 2) tgsis.vertices_at uses; empty when it does not exist at t';

-- ==== temporal/exists_at.sql ====
-- tgsis.exists_at(geoid, t, convention): whether a geometry exists at model time t (static ones always do).
CREATE FUNCTION tgsis.exists_at(p_geoid bigint, p_t double precision, p_convention text DEFAULT 'left')
RETURNS boolean
LANGUAGE sql
STABLE
PARALLEL SAFE
AS $$
    SELECT CASE g.timemodel
               WHEN 'STATIC' THEN true
               WHEN 'INSTANTS' THEN tgsis.instant_at(p_geoid, p_t, p_convention) IS NOT NULL
               ELSE EXISTS (SELECT FROM tgsis.evolving_frame(p_geoid, p_t))
           END
      FROM tgsis.geometry g
     WHERE g.geoid = p_geoid
       AND tgsis.checked_convention(p_convention) IS NOT NULL  -- an error for every model, not only model 2
$$;

COMMENT ON FUNCTION tgsis.exists_at(bigint, double precision, text) IS
    'whether a geometry exists at model time t: static always; temporal ones from their first instant to their last (for ever after if alive); NULL if there is no such geometry';

-- ==== temporal/features_at.sql ====
-- tgsis.features_at(class, t, convention): the features of a class that exist at model time t.
CREATE FUNCTION tgsis.features_at(p_class text, p_t double precision, p_convention text DEFAULT 'left')
RETURNS SETOF bigint
LANGUAGE plpgsql
STABLE
AS $$
DECLARE
    v_class tgsis.catalog := tgsis.catalog_row(p_class);
BEGIN
    PERFORM tgsis.checked_time(p_t), tgsis.checked_convention(p_convention);
    RETURN QUERY EXECUTE format('SELECT f._geoid FROM %I.%I f WHERE tgsis.exists_at(f._geoid, $1, $2) ORDER BY f._geoid',
                                v_class.schemaname, v_class.featuretable)
        USING p_t, p_convention;
END
$$;

COMMENT ON FUNCTION tgsis.features_at(text, double precision, text) IS
    'ids of the features of a class that exist at model time t (static: all; temporal: from their first instant to their last, or for ever after if alive), ascending';

-- ==== temporal/surfaces_at.sql ====
-- tgsis.surfaces_at(class, t, convention): every feature of a class that exists at t with its surface then, as arrays.
-- vertices is n x 3 (x, y, z, in vertex-id order); triangles is m x 3 and
-- holds 0-based positions in vertices, so each row is a mesh by itself.
CREATE FUNCTION tgsis.surfaces_at(p_class text, p_t double precision, p_convention text DEFAULT 'left')
RETURNS TABLE (geoid bigint, vertices double precision[], triangles bigint[])
LANGUAGE plpgsql
STABLE
AS $$
DECLARE
    v_class tgsis.catalog := tgsis.catalog_row(p_class);
BEGIN
    IF v_class.geotype <> 'SURFACE' THEN
        RAISE EXCEPTION 'feature class % holds % features, not surfaces', p_class, v_class.geotype
            USING ERRCODE = 'TG100', HINT = 'tgsis.features_at lists the features of any class that exist at t';
    END IF;
    PERFORM tgsis.checked_time(p_t), tgsis.checked_convention(p_convention);
    RETURN QUERY EXECUTE format($q$
        WITH f AS (
            SELECT _geoid AS geoid FROM %I.%I WHERE tgsis.exists_at(_geoid, $1, $2)
        ), v AS (
            SELECT f.geoid, v.vrtxid, v.x, v.y, v.z, row_number() OVER (PARTITION BY f.geoid ORDER BY v.vrtxid) - 1 AS pos
              FROM f, tgsis.vertices_at(f.geoid, $1, $2) v
        ), c AS (
            SELECT f.geoid, c.trglid, p1.pos AS pos1, p2.pos AS pos2, p3.pos AS pos3
              FROM f
             CROSS JOIN LATERAL tgsis.triangles_at(f.geoid, $1, $2) c
              JOIN v p1 ON p1.geoid = f.geoid AND p1.vrtxid = c.vrtxid1
              JOIN v p2 ON p2.geoid = f.geoid AND p2.vrtxid = c.vrtxid2
              JOIN v p3 ON p3.geoid = f.geoid AND p3.vrtxid = c.vrtxid3
        )
        SELECT f.geoid,
               (SELECT array_agg(ARRAY[v.x, v.y, v.z] ORDER BY v.pos) FROM v WHERE v.geoid = f.geoid),
               (SELECT array_agg(ARRAY[c.pos1, c.pos2, c.pos3] ORDER BY c.trglid) FROM c WHERE c.geoid = f.geoid)
          FROM f
         ORDER BY f.geoid
        $q$, v_class.schemaname, v_class.featuretable)
        USING p_t, p_convention;
END
$$;

COMMENT ON FUNCTION tgsis.surfaces_at(text, double precision, text) IS
    'every feature of a SURFACE class that exists at model time t with its shape then: vertices (n x 3 array) and triangles (m x 3 array of 0-based positions in vertices)';

-- ==== temporal/geometry_instants.sql ====
-- tgsis.geometry_instants(geoid): the instants of a temporal geometry, ascending, and whether its topology is (re)defined there.
-- Model 2: every instant (each has its own triangles). Model 3: every
-- geometry instant; topology is true at the start of each period.
CREATE FUNCTION tgsis.geometry_instants(p_geoid bigint)
RETURNS TABLE (t double precision, topology boolean)
LANGUAGE sql
STABLE
PARALLEL SAFE
AS $$
    SELECT i.times, true FROM tgsis.times i WHERE i.geoid = p_geoid
    UNION ALL
    SELECT i.timet, bool_or(i.timet = i.timem) FROM tgsis.timet i WHERE i.geoid = p_geoid GROUP BY i.timet
    ORDER BY 1
$$;

COMMENT ON FUNCTION tgsis.geometry_instants(bigint) IS
    'instants of a temporal geometry in ascending order, with topology = true where its topology is (re)defined (every instant of model 2, period starts of model 3); empty for static geometries';

-- ==== temporal/temporal_geometry.sql ====
-- tgsis.temporal_geometry(geoid, time model): lock and check a geometry of that time model; TG200 / TG100 naming it otherwise.
CREATE FUNCTION tgsis.temporal_geometry(p_geoid bigint, p_time_model text)
RETURNS void
LANGUAGE plpgsql
AS $$
DECLARE
    v_model text;
BEGIN
    SELECT timemodel INTO v_model FROM tgsis.geometry WHERE geoid = p_geoid FOR UPDATE;
    IF NOT FOUND THEN
        RAISE EXCEPTION 'geometry % does not exist', p_geoid
            USING ERRCODE = 'TG200', HINT = 'SELECT geoid FROM tgsis.geometry lists the stored geometries';
    ELSIF v_model <> p_time_model THEN
        RAISE EXCEPTION 'geometry % has time model %, not %', p_geoid, v_model, p_time_model
            USING ERRCODE = 'TG100',
                  HINT = 'instants are added to and deleted from surfaces of INSTANTS classes (model 2)';
    END IF;
END
$$;

COMMENT ON FUNCTION tgsis.temporal_geometry(bigint, text) IS
    'lock a geometry row and check its time model (TG200 if it does not exist, TG100 if its time model differs)';

-- ==== temporal/timerange.sql ====
-- tgsis.timerange: an interval of model time (double precision), for the
-- answers of the temporal questions (tgsis.property_periods). Bounds may be
-- open or closed, '[t, t]' is a single instant, and an unbounded end ('[t,)')
-- means for ever (an alive feature after its last instant). The multirange
-- type tgsis.timemultirange comes with it; range_agg merges overlapping and
-- adjacent intervals ('[1,2)' and '[2,3]' give '[1,3]', '(1,2)' and '(2,3)' stay two).
-- Its constructor functions tgsis.timerange(lower, upper[, bounds]) and
-- tgsis.timemultirange(...) belong to the bootstrap superuser whoever runs
-- this, so an installer that is not a superuser could not comment on them:
-- the type comments document them.
CREATE TYPE tgsis.timerange AS RANGE (
    subtype              = double precision,
    subtype_diff         = float8mi,
    multirange_type_name = tgsis.timemultirange
);

COMMENT ON TYPE tgsis.timerange IS
    'interval of model time (double precision) with open or closed bounds, made by tgsis.timerange(lower, upper, ''[)'') (NULL bound: unbounded; unbounded upper end: for ever)';
COMMENT ON TYPE tgsis.timemultirange IS
    'set of disjoint intervals of model time (multirange of tgsis.timerange), made by tgsis.timemultirange(range, ...) which merges overlapping and adjacent ones';

-- ==== temporal/invalid_period.sql ====
-- tgsis.invalid_period(names, t0, t1): raise TG100 for two model times that are no period (NaN, or the first after the second).
-- The interval helpers (tgsis.linear_satisfied, tgsis.evolving_satisfied)
-- are SQL functions that the planner inlines into the temporal questions;
-- they call this only in the CASE branch of bad arguments, so the good case
-- costs two comparisons and NaN never reaches a tgsis.timerange (where it
-- made a range '[0,NaN)', or PostgreSQL's raw 22000 for a reversed one).
CREATE FUNCTION tgsis.invalid_period(p_names text, p_t0 double precision, p_t1 double precision)
RETURNS tgsis.timemultirange
LANGUAGE plpgsql
IMMUTABLE
PARALLEL SAFE
AS $$
BEGIN
    RAISE EXCEPTION '% = % and % are no period of model time', p_names, p_t0, p_t1
        USING ERRCODE = 'TG100',
              DETAIL = 'A period needs two numbers (not NaN), the first not after the second.',
              HINT = format('give %s in order; -Infinity and Infinity are allowed', p_names);
END
$$;

COMMENT ON FUNCTION tgsis.invalid_period(text, double precision, double precision) IS
    'raise TG100 naming the arguments p_names whose model times t0, t1 are no period (NaN, or t0 after t1); used by the interval helpers of the temporal questions';

-- ==== temporal/checked_operator.sql ====
-- tgsis.checked_operator(op): a comparison operator of the temporal questions ('<', '<=', '>', '>=', '=' or '<>'), or TG100 naming it.
CREATE FUNCTION tgsis.checked_operator(p_op text)
RETURNS text
LANGUAGE plpgsql
IMMUTABLE
PARALLEL SAFE
AS $$
BEGIN
    IF p_op IN ('<', '<=', '>', '>=', '=', '<>') THEN
        RETURN p_op;
    END IF;
    RAISE EXCEPTION 'comparison operator % is not one of <, <=, >, >=, =, <>', coalesce(quote_literal(p_op), 'NULL')
        USING ERRCODE = 'TG100',
              HINT = 'the condition is "value op v", e.g. op => ''>='' for values of at least v';
END
$$;

COMMENT ON FUNCTION tgsis.checked_operator(text) IS
    'a comparison operator of the temporal questions: <, <=, >, >=, = or <>; TG100 otherwise';

-- ==== temporal/satisfies.sql ====
-- tgsis.satisfies(x, op, v): whether x op v holds; NULL (unknown) when x is NULL or NaN. op must come from tgsis.checked_operator.
CREATE FUNCTION tgsis.satisfies(p_x double precision, p_op text, p_v double precision)
RETURNS boolean
LANGUAGE sql
IMMUTABLE
PARALLEL SAFE
AS $$
    SELECT CASE WHEN p_x = 'NaN' THEN NULL
                WHEN p_op = '<' THEN p_x < p_v
                WHEN p_op = '<=' THEN p_x <= p_v
                WHEN p_op = '>' THEN p_x > p_v
                WHEN p_op = '>=' THEN p_x >= p_v
                WHEN p_op = '=' THEN p_x = p_v
                WHEN p_op = '<>' THEN p_x <> p_v
           END
$$;

COMMENT ON FUNCTION tgsis.satisfies(double precision, text, double precision) IS
    'x op v for op in <, <=, >, >=, =, <>; NULL (condition unknown) when x is NULL or NaN';

-- ==== temporal/crossing_time.sql ====
-- tgsis.crossing_time(t0, t1, a, b, v): where a value going linearly from a at t0 to b at t1 equals v, t0 + (v - a) / (b - a) (t1 - t0), kept inside [t0, t1].
-- For a <> b and v between them; rounding may land it on t0 or t1.
CREATE FUNCTION tgsis.crossing_time(p_t0 double precision, p_t1 double precision, p_a double precision,
                                    p_b double precision, p_v double precision)
RETURNS double precision
LANGUAGE sql
IMMUTABLE
PARALLEL SAFE
AS $$
    SELECT greatest(p_t0, least(p_t1, p_t0 + (p_v - p_a) / (p_b - p_a) * (p_t1 - p_t0)))
$$;

COMMENT ON FUNCTION tgsis.crossing_time(double precision, double precision, double precision, double precision, double precision) IS
    'time in [t0, t1] at which a value linear from a (at t0) to b (at t1) equals v: t0 + (v - a)/(b - a) (t1 - t0), clamped; for a <> b with v between them';

-- ==== temporal/linear_satisfied.sql ====
-- tgsis.linear_satisfied(t0, t1, a, b, op, v): the times inside the open interval (t0, t1) at which a value going linearly from a (at t0) to b (at t1) satisfies "value op v".
-- Where the value crosses v strictly inside, at tc = tgsis.crossing_time, the
-- pieces are (t0, tc), [tc, tc] and (tc, t1), each kept when the sign of
-- value - v there satisfies op (strict operators leave tc out, non-strict
-- ones keep it). Otherwise value - v has one sign on the whole open interval
-- (0 only when a = b = v). Unknown (empty) when a or b is NULL, NaN or
-- infinite, or when there is no t1.
CREATE FUNCTION tgsis.linear_satisfied(p_t0 double precision, p_t1 double precision, p_a double precision,
                                       p_b double precision, p_op text, p_v double precision)
RETURNS tgsis.timemultirange
LANGUAGE sql
IMMUTABLE
PARALLEL SAFE
AS $$
    SELECT CASE
               WHEN p_t0 = 'NaN' OR p_t1 = 'NaN' OR p_t0 > p_t1
                   THEN tgsis.invalid_period('p_t0, p_t1', p_t0, p_t1)
               WHEN p_t1 IS NULL
                    OR NOT coalesce(p_a > '-Infinity' AND p_a < 'Infinity' AND p_b > '-Infinity' AND p_b < 'Infinity', false)
                   THEN tgsis.timemultirange()
               WHEN least(p_a, p_b) < p_v AND p_v < greatest(p_a, p_b)
                   THEN tgsis.timemultirange(
                            CASE WHEN tgsis.satisfies(sign(p_a - p_v), p_op, 0)
                                 THEN tgsis.timerange(p_t0, tgsis.crossing_time(p_t0, p_t1, p_a, p_b, p_v), '()')
                                 ELSE 'empty' END,
                            CASE WHEN tgsis.satisfies(0, p_op, 0)
                                 THEN tgsis.timerange(tgsis.crossing_time(p_t0, p_t1, p_a, p_b, p_v),
                                                      tgsis.crossing_time(p_t0, p_t1, p_a, p_b, p_v), '[]')
                                 ELSE 'empty' END,
                            CASE WHEN tgsis.satisfies(sign(p_b - p_v), p_op, 0)
                                 THEN tgsis.timerange(tgsis.crossing_time(p_t0, p_t1, p_a, p_b, p_v), p_t1, '()')
                                 ELSE 'empty' END)
                        * tgsis.timemultirange(tgsis.timerange(p_t0, p_t1, '()'))
               WHEN tgsis.satisfies(sign(sign(p_a - p_v) + sign(p_b - p_v)), p_op, 0)
                   THEN tgsis.timemultirange(tgsis.timerange(p_t0, p_t1, '()'))
               ELSE tgsis.timemultirange()
           END
$$;

COMMENT ON FUNCTION tgsis.linear_satisfied(double precision, double precision, double precision, double precision, text, double precision) IS
    'the times in the open interval (t0, t1) at which a value linear from a (at t0) to b (at t1) satisfies value op v, crossings by linear interpolation; empty when a or b is NULL or not finite';

-- ==== temporal/instant_periods.sql ====
-- tgsis.instant_periods(geoid, convention): every instant of a model-2 surface with the interval in which its shape and values hold.
-- left-closed: '[t_i, t_i+1)'; the last instant '[t_k, t_k]', or '[t_k,)' if
-- the geometry is alive. right-closed: the first instant '[t_0, t_0]', then
-- '(t_i-1, t_i]'; the last '(t_k-1,)' if alive. The intervals do not overlap
-- and cover the feature's life, as tgsis.instant_at chooses.
CREATE FUNCTION tgsis.instant_periods(p_geoid bigint, p_convention text DEFAULT 'left')
RETURNS TABLE (times double precision, period tgsis.timerange)
LANGUAGE sql
STABLE
PARALLEL SAFE
AS $$
    SELECT s.times,
           CASE WHEN tgsis.checked_convention(p_convention) = 'left'
                THEN tgsis.timerange(s.times, CASE WHEN s.next IS NOT NULL THEN s.next WHEN NOT g.alive THEN s.times END,
                                     CASE WHEN s.next IS NULL AND NOT g.alive THEN '[]' ELSE '[)' END)
                ELSE tgsis.timerange(coalesce(s.prev, s.times), CASE WHEN s.next IS NOT NULL OR NOT g.alive THEN s.times END,
                                     CASE WHEN s.prev IS NULL THEN '[]' ELSE '(]' END)
           END
      FROM (SELECT i.times, lag(i.times) OVER w AS prev, lead(i.times) OVER w AS next
              FROM tgsis.times i
             WHERE i.geoid = p_geoid
            WINDOW w AS (ORDER BY i.times)) s
      JOIN tgsis.geometry g ON g.geoid = p_geoid
$$;

COMMENT ON FUNCTION tgsis.instant_periods(bigint, text) IS
    'model 2: each instant of a surface with the interval in which it holds under the left- or right-closed step convention (unbounded after the last instant of an alive geometry)';

-- ==== temporal/evolving_instants.sql ====
-- tgsis.evolving_instants(geoid): every geometry instant of a model-3 surface with what its values are linear to and how long its period lasts.
-- timem / next_timem: its topology period [timem, next_timem) (next_timem NULL
-- for the last period); t_next: the next geometry instant of the period (NULL
-- at the period's last); hold: whether the values of the period's last
-- instant hold after it (until the next period, or for ever if alive).
CREATE FUNCTION tgsis.evolving_instants(p_geoid bigint)
RETURNS TABLE (timem double precision, next_timem double precision, timet double precision,
               t_next double precision, hold boolean)
LANGUAGE sql
STABLE
PARALLEL SAFE
AS $$
    SELECT i.timem, m.next_timem, i.timet, lead(i.timet) OVER (PARTITION BY i.timem ORDER BY i.timet),
           m.next_timem IS NOT NULL OR g.alive
      FROM tgsis.timet i
      JOIN (SELECT t.timem, lead(t.timem) OVER (ORDER BY t.timem) AS next_timem
              FROM tgsis.timem t
             WHERE t.geoid = p_geoid) m ON m.timem = i.timem
      JOIN tgsis.geometry g ON g.geoid = p_geoid
     WHERE i.geoid = p_geoid
$$;

COMMENT ON FUNCTION tgsis.evolving_instants(bigint) IS
    'model 3: geometry instants of a surface with their period [timem, next_timem), the next geometry instant of the period (t_next) and whether the last values hold after the period (hold)';

-- ==== temporal/evolving_satisfied.sql ====
-- tgsis.evolving_satisfied(timem, next_timem, t, t_next, a, b, hold, op, v): the times from model-3 geometry instant t up to the next one at which "value op v" holds.
-- The arguments but a, b, op and v are a row of tgsis.evolving_instants. The
-- value a at t holds at t itself; from t to t_next (the next geometry
-- instant of the period, value b there) the value is linear
-- (tgsis.linear_satisfied); after the period's last instant (t_next NULL) a
-- holds for ever when hold is true (a later period follows, or the feature
-- is alive). All of it is cut to the period's time [timem, next_timem): at a
-- topology change the new period applies. NULL or NaN values are unknown.
CREATE FUNCTION tgsis.evolving_satisfied(p_timem double precision, p_next_timem double precision, p_t double precision,
                                         p_t_next double precision, p_a double precision, p_b double precision,
                                         p_hold boolean, p_op text, p_v double precision)
RETURNS tgsis.timemultirange
LANGUAGE sql
IMMUTABLE
PARALLEL SAFE
AS $$
    SELECT CASE WHEN p_timem = 'NaN' OR p_next_timem = 'NaN' OR p_timem > p_next_timem
                THEN tgsis.invalid_period('p_timem, p_next_timem', p_timem, p_next_timem)
                WHEN p_t = 'NaN'
                THEN tgsis.invalid_period('p_timem, p_t', p_timem, p_t)
           ELSE (tgsis.timemultirange(CASE WHEN tgsis.satisfies(p_a, p_op, p_v)
                                      THEN tgsis.timerange(p_t, CASE WHEN p_t_next IS NULL AND p_hold THEN NULL ELSE p_t END, '[]')
                                      ELSE 'empty' END)
            + tgsis.linear_satisfied(p_t, p_t_next, p_a, p_b, p_op, p_v))
           * tgsis.timemultirange(tgsis.timerange(p_timem, p_next_timem, '[)')) END
$$;

COMMENT ON FUNCTION tgsis.evolving_satisfied(double precision, double precision, double precision, double precision, double precision, double precision, boolean, text, double precision) IS
    'model 3: the times in [t, t_next) (after the last instant of a period: [t, next period) or for ever if hold) at which a value a at t, linear to b at t_next, satisfies value op v; cut to the period [timem, next_timem)';

-- ==== temporal/checked_question.sql ====
-- tgsis.checked_question(class, geoid, property, per_cell, op, value, convention): the catalog row of the temporal class a question "property op value" is asked of, once the question makes sense.
-- Checks, in this order: the class exists (TG200) and is temporal (TG100);
-- the property is a numeric per-instant property (column of <class>_pros) or,
-- with per_cell, a numeric vertex or cell property (<class>_cellpros) of it
-- (TG103, naming it); the operator (tgsis.checked_operator), the value (a
-- number: TG100 for NULL or NaN) and the convention (tgsis.checked_convention);
-- the feature is one of the class (TG200).
CREATE FUNCTION tgsis.checked_question(p_class text, p_geoid bigint, p_property text, p_per_cell boolean,
                                       p_op text, p_value double precision, p_convention text)
RETURNS tgsis.catalog
LANGUAGE plpgsql
STABLE
AS $$
DECLARE
    v_class tgsis.catalog := tgsis.catalog_row(p_class);
    v_what  text := CASE WHEN p_per_cell THEN lower(v_class.proalignment) ELSE 'per-instant' END;
    v_props jsonb := CASE WHEN p_per_cell THEN v_class.cell_properties ELSE v_class.instant_properties END;
    v_type  text;
    v_found boolean;
BEGIN
    IF v_class.timemodel = 'STATIC' THEN
        RAISE EXCEPTION 'feature class % is static: its properties do not change in time', p_class
            USING ERRCODE = 'TG100', HINT = 'temporal questions are asked of INSTANTS (model 2) and EVOLVING (model 3) classes';
    END IF;
    SELECT p ->> 'type' INTO v_type FROM jsonb_array_elements(v_props) p WHERE p ->> 'name' = p_property;
    IF v_type IS NULL THEN
        RAISE EXCEPTION 'feature class % has no % property %', p_class, v_what, coalesce(quote_literal(p_property), 'NULL')
            USING ERRCODE = 'TG103',
                  HINT = CASE WHEN EXISTS (SELECT FROM jsonb_array_elements(CASE WHEN p_per_cell THEN v_class.instant_properties
                                                                                 ELSE v_class.cell_properties END) p
                                            WHERE p ->> 'name' = p_property)
                              THEN format('%s is a %s property: ask tgsis.%s', p_property,
                                          CASE WHEN p_per_cell THEN 'per-instant' ELSE lower(v_class.proalignment) END,
                                          CASE WHEN p_per_cell THEN 'property_periods' ELSE 'first_time' END)
                              ELSE format('its %s properties: %s', v_what,
                                          coalesce((SELECT string_agg(p ->> 'name', ', ') FROM jsonb_array_elements(v_props) p),
                                                   'none'))
                         END;
    END IF;
    IF v_type NOT IN ('smallint', 'integer', 'bigint', 'real', 'double precision', 'numeric') THEN
        RAISE EXCEPTION '% property % of feature class % is %, not a number', v_what, p_property, p_class, v_type
            USING ERRCODE = 'TG103', HINT = 'conditions "value op v" are asked of numeric properties';
    END IF;
    PERFORM tgsis.checked_operator(p_op);
    IF p_value IS NULL OR p_value = 'NaN' THEN
        RAISE EXCEPTION 'the value % is compared with must be a number, not %', p_property, coalesce(p_value::text, 'NULL')
            USING ERRCODE = 'TG100', HINT = '-Infinity and Infinity are allowed';
    END IF;
    PERFORM tgsis.checked_convention(p_convention);
    EXECUTE format('SELECT EXISTS (SELECT FROM %I.%I WHERE _geoid = $1)', v_class.schemaname, v_class.featuretable)
       INTO v_found USING p_geoid;
    IF NOT v_found THEN
        RAISE EXCEPTION 'feature % is not a feature of class %', coalesce(p_geoid::text, 'NULL'), p_class
            USING ERRCODE = 'TG200', HINT = format('SELECT _geoid FROM %I.%I lists them', v_class.schemaname, v_class.featuretable);
    END IF;
    RETURN v_class;
END
$$;

COMMENT ON FUNCTION tgsis.checked_question(text, bigint, text, boolean, text, double precision, text) IS
    'the catalog row of the temporal class a question "property op value" is asked of, after checking it is temporal (TG100), the property is a numeric per-instant (or, per_cell, vertex/cell) property of it (TG103), op, value and convention (TG100) and that the feature is one of its (TG200)';

-- ==== temporal/property_periods.sql ====
-- tgsis.property_periods(class, geoid, property, op, value, convention): the maximal intervals of model time over which "property op value" holds for a per-instant property of a feature, ascending.
-- Model 2 (INSTANTS): the value of instant t_i holds in its step interval
-- (tgsis.instant_periods: left-closed '[t_i, t_i+1)', the last '[t_k, t_k]';
-- right-closed '(t_i-1, t_i]', the first '[t_0, t_0]'; after the last '[t_k,)'
-- or '(t_k-1,)' if alive). Model 3 (EVOLVING): the value is linear between
-- consecutive geometry instants of a topology period, crossing times by linear
-- interpolation, bounds closed for <=, >=, = and open for <, >, <> at a
-- crossing (tgsis.evolving_satisfied); convention is not used. NULL or NaN
-- values are unknown: never satisfied, nor the stretches next to them
-- (model 3). Adjacent pieces are merged ('[1,2)' and '[2,3)' give '[1,3)').
-- An alive feature keeps its last value: the last interval may be unbounded
-- ('[t,)'). When the property first satisfies the condition is
-- lower(period) of the first row (open lower bound: right after it).
CREATE FUNCTION tgsis.property_periods(p_class text, p_geoid bigint, p_property text, p_op text,
                                       p_value double precision, p_convention text DEFAULT 'left')
RETURNS TABLE (period tgsis.timerange)
LANGUAGE plpgsql
STABLE
AS $$
DECLARE
    v_class tgsis.catalog := tgsis.checked_question(p_class, p_geoid, p_property, false, p_op, p_value, p_convention);
    v_pieces text;
BEGIN
    IF v_class.timemodel = 'INSTANTS' THEN
        v_pieces := format($q$
            SELECT i.period AS r
              FROM tgsis.instant_periods($1, $4) i
              JOIN %I.%I p ON p._geoid = $1 AND p._times = i.times
             WHERE tgsis.satisfies(p.%I::double precision, $2, $3)
            $q$, v_class.schemaname, v_class.protablename, p_property);
    ELSE
        v_pieces := format($q$
            SELECT x.r
              FROM (SELECT i.*, p.%1$I::double precision AS a,
                           lead(p.%1$I::double precision) OVER (PARTITION BY i.timem ORDER BY i.timet) AS b
                      FROM tgsis.evolving_instants($1) i
                      LEFT JOIN %2$I.%3$I p ON p._geoid = $1 AND p._timem = i.timem AND p._timet = i.timet) s,
                   unnest(tgsis.evolving_satisfied(s.timem, s.next_timem, s.timet, s.t_next, s.a, s.b, s.hold, $2, $3)) x(r)
            $q$, p_property, v_class.schemaname, v_class.protablename);
    END IF;
    RETURN QUERY EXECUTE format('SELECT u.r FROM (SELECT range_agg(p.r) AS m FROM (%s) p) a, unnest(a.m) u(r) ORDER BY 1',
                                v_pieces)
        USING p_geoid, p_op, p_value, p_convention;
END
$$;

COMMENT ON FUNCTION tgsis.property_periods(text, bigint, text, text, double precision, text) IS
    'maximal intervals of model time (tgsis.timerange) in which a numeric per-instant property of a feature satisfies property op value (op: <, <=, >, >=, =, <>): model 2 stepwise by the left- or right-closed convention, model 3 linear between geometry instants; NULL and NaN values never satisfy it';

-- ==== temporal/class_property_periods.sql ====
-- tgsis.class_property_periods(class, property, op, value, convention): for every feature of a class, the periods over which "property op value" holds.
-- The source design's manager asked this of a whole class ("the features
-- whose throw exceeds 100 m, and when"): tgsis.property_periods for each
-- feature of the class, in one query. Features for which the condition
-- never holds give no row; the first row of a feature starts when the
-- property first satisfies the condition.
CREATE FUNCTION tgsis.class_property_periods(p_class text, p_property text, p_op text, p_value double precision,
                                             p_convention text DEFAULT 'left')
RETURNS TABLE (geoid bigint, period tgsis.timerange)
LANGUAGE plpgsql
STABLE
AS $$
DECLARE
    v_class tgsis.catalog := tgsis.catalog_row(p_class);
    v_first bigint;
BEGIN
    IF v_class.timemodel = 'STATIC' THEN
        RAISE EXCEPTION 'feature class % is static: its properties do not change in time', p_class
            USING ERRCODE = 'TG100', HINT = 'ask this of an INSTANTS or EVOLVING class';
    END IF;
    EXECUTE format('SELECT min(_geoid) FROM %I.%I', v_class.schemaname, v_class.featuretable) INTO v_first;
    IF v_first IS NULL THEN
        RETURN;   -- no feature: nothing holds (and nothing to check the question against)
    END IF;
    -- the question checked once (property, operator, value, convention), with its errors, before the scan
    PERFORM tgsis.checked_question(p_class, v_first, p_property, false, p_op, p_value, p_convention);
    RETURN QUERY EXECUTE format(
        'SELECT f._geoid, p.period FROM %I.%I f, LATERAL tgsis.property_periods($1, f._geoid, $2, $3, $4, $5) p
          ORDER BY f._geoid, lower(p.period) NULLS FIRST',
        v_class.schemaname, v_class.featuretable)
      USING p_class, p_property, p_op, p_value, p_convention;
END
$$;

COMMENT ON FUNCTION tgsis.class_property_periods(text, text, text, double precision, text) IS
    'for every feature of a temporal class, the maximal periods over which a per-instant property satisfies "property op value" (tgsis.property_periods per feature), by feature and start';

-- ==== temporal/first_time.sql ====
-- tgsis.first_time(class, geoid, property, op, value, convention): for each vertex/node or cell of a feature, the first time at which its property satisfies "property op value"; cells that never do are left out.
-- The first time is the infimum of the times at which it holds; the condition
-- may hold only right after it. Model 2 (INSTANTS): the smallest lower bound of
-- the step intervals (tgsis.instant_periods) of the instants whose value
-- satisfies it: left-closed t_i itself; right-closed t_i-1 (the value of t_i
-- holds from right after t_i-1), t_0 for the first instant. Model 3
-- (EVOLVING): a node or triangle belongs to one topology period and its value
-- is linear between the period's geometry instants (tgsis.evolving_satisfied;
-- a missing sample makes the stretches next to it unknown); convention is not
-- used. NaN values are unknown. One set-based query.
CREATE FUNCTION tgsis.first_time(p_class text, p_geoid bigint, p_property text, p_op text,
                                 p_value double precision, p_convention text DEFAULT 'left')
RETURNS TABLE (idx bigint, t double precision)
LANGUAGE plpgsql
STABLE
AS $$
DECLARE
    v_class tgsis.catalog := tgsis.checked_question(p_class, p_geoid, p_property, true, p_op, p_value, p_convention);
    v_first text;
BEGIN
    IF v_class.timemodel = 'INSTANTS' THEN
        v_first := format($q$
            SELECT c._idx, min(lower(i.period))
              FROM %I.%I c
              JOIN tgsis.instant_periods($1, $4) i ON i.times = c._times
             WHERE c._geoid = $1 AND tgsis.satisfies(c.%I::double precision, $2, $3)
             GROUP BY c._idx
            $q$, v_class.schemaname, v_class.cellprotable, p_property);
    ELSE
        v_first := format($q$
            SELECT c._idx, min(lower(tgsis.evolving_satisfied(i.timem, i.next_timem, i.timet, i.t_next, c.a,
                                                             CASE WHEN c.c_next = i.t_next THEN c.b END, i.hold, $2, $3)))
              FROM (SELECT c._idx, c._timem, c._timet, c.%1$I::double precision AS a,
                           lead(c._timet) OVER w AS c_next, lead(c.%1$I::double precision) OVER w AS b
                      FROM %2$I.%3$I c
                     WHERE c._geoid = $1
                    WINDOW w AS (PARTITION BY c._idx, c._timem ORDER BY c._timet)) c
              JOIN tgsis.evolving_instants($1) i ON i.timem = c._timem AND i.timet = c._timet
             GROUP BY c._idx
            $q$, p_property, v_class.schemaname, v_class.cellprotable);
    END IF;
    RETURN QUERY EXECUTE format('SELECT f.* FROM (%s) f(idx, t) WHERE f.t IS NOT NULL ORDER BY f.idx', v_first)
        USING p_geoid, p_op, p_value, p_convention;
END
$$;

COMMENT ON FUNCTION tgsis.first_time(text, bigint, text, text, double precision, text) IS
    'for each vertex/node or cell of a feature, the first (infimum) model time at which a numeric cell property satisfies property op value: model 2 stepwise (left-closed t_i, right-closed t_i-1), model 3 linear between the geometry instants of its period; cells that never do are left out';

-- ==== model2/add_instant.sql ====
-- tgsis.add_instant(geoid, t): record a new instant of a model-2 surface; the caller then stores its vertices, triangles and properties there.
CREATE FUNCTION tgsis.add_instant(p_geoid bigint, p_t double precision)
RETURNS void
LANGUAGE plpgsql
AS $$
BEGIN
    PERFORM tgsis.plain_write_check('tgsis', 'times');  -- not "in" a version while features are plain
    PERFORM tgsis.temporal_geometry(p_geoid, 'INSTANTS');
    IF p_t IS NULL OR p_t IN ('NaN', 'Infinity', '-Infinity') THEN
        RAISE EXCEPTION 'instant % of geometry % must be a finite number', coalesce(p_t::text, 'NULL'), p_geoid
            USING ERRCODE = 'TG100';
    END IF;
    IF EXISTS (SELECT FROM tgsis.times WHERE geoid = p_geoid AND times = p_t) THEN
        RAISE EXCEPTION 'geometry % has an instant % already', p_geoid, p_t
            USING ERRCODE = 'TG201', HINT = 'tgsis.delete_instant removes it first';
    END IF;
    INSERT INTO tgsis.times (geoid, times) VALUES (p_geoid, p_t);
END
$$;

COMMENT ON FUNCTION tgsis.add_instant(bigint, double precision) IS
    'model 2: add instant t to a surface (TG201 if it has it already); its vertices, triangles and properties are stored next in the same transaction';

-- ==== model2/delete_instant.sql ====
-- tgsis.delete_instant(geoid, t): remove one instant of a model-2 surface with its vertices, triangles and properties.
-- Refuses (TG202) the only instant: that is deleting the feature.
CREATE FUNCTION tgsis.delete_instant(p_geoid bigint, p_t double precision)
RETURNS boolean
LANGUAGE plpgsql
AS $$
DECLARE
    v_class tgsis.catalog;
BEGIN
    PERFORM tgsis.plain_write_check('tgsis', 'times');  -- not "in" a version while features are plain
    PERFORM tgsis.temporal_geometry(p_geoid, 'INSTANTS');
    IF NOT EXISTS (SELECT FROM tgsis.times WHERE geoid = p_geoid AND times = p_t) THEN
        RETURN false;
    END IF;
    IF NOT EXISTS (SELECT FROM tgsis.times WHERE geoid = p_geoid AND times <> p_t) THEN
        RAISE EXCEPTION 'instant % is the only one of geometry %', p_t, p_geoid
            USING ERRCODE = 'TG202', HINT = format('SELECT tgsis.delete_geometry(%s) deletes the feature', p_geoid);
    END IF;
    FOR v_class IN SELECT * FROM tgsis.catalog WHERE timemodel = 'INSTANTS' LOOP
        EXECUTE format('DELETE FROM %I.%I WHERE _geoid = $1 AND _times = $2', v_class.schemaname, v_class.cellprotable)
          USING p_geoid, p_t;
        EXECUTE format('DELETE FROM %I.%I WHERE _geoid = $1 AND _times = $2', v_class.schemaname, v_class.protablename)
          USING p_geoid, p_t;
    END LOOP;
    DELETE FROM tgsis.times_trgl WHERE geoid = p_geoid AND times = p_t;
    DELETE FROM tgsis.times_vrtx WHERE geoid = p_geoid AND times = p_t;
    DELETE FROM tgsis.times WHERE geoid = p_geoid AND times = p_t;
    PERFORM tgsis.refresh_geometry(p_geoid);
    RETURN true;
END
$$;

COMMENT ON FUNCTION tgsis.delete_instant(bigint, double precision) IS
    'model 2: delete instant t of a surface with its vertices, triangles and per-instant and cell properties, in the session''s version; false if it had no such instant; TG202 for its only instant';

-- ==== model3/delete_period.sql ====
-- tgsis.delete_period(geoid, timem): remove the first or the last topology period of a model-3 surface, with its nodes, triangles, positions and properties.
-- The periods of an evolving surface follow each other (each ends where the
-- next starts), so only an end period can go: a middle one would leave a
-- gap (TG202), and the only one is the whole feature (TG202). With the last
-- period gone the surface ends at the last geometry instant of the one
-- before (alive or not as before); with the first gone it starts where the
-- second starts. Returns false when no period starts at timem.
CREATE FUNCTION tgsis.delete_period(p_geoid bigint, p_timem double precision)
RETURNS boolean
LANGUAGE plpgsql
AS $$
DECLARE
    v_first double precision;
    v_last  double precision;
    v_count bigint;
    v_class tgsis.catalog;
BEGIN
    PERFORM tgsis.plain_write_check('tgsis', 'timem');  -- not "in" a version while features are plain
    PERFORM tgsis.temporal_geometry(p_geoid, 'EVOLVING');
    -- one writer of the feature's periods at a time (tgsis.append_period locks the same row)
    PERFORM FROM tgsis.geometry WHERE geoid = p_geoid FOR UPDATE;
    IF NOT EXISTS (SELECT FROM tgsis.timem WHERE geoid = p_geoid AND timem = p_timem) THEN
        RETURN false;
    END IF;
    SELECT min(timem), max(timem), count(*) INTO v_first, v_last, v_count FROM tgsis.timem WHERE geoid = p_geoid;
    IF v_count = 1 THEN
        RAISE EXCEPTION 'the topology period from % is the only one of geometry %', p_timem, p_geoid
            USING ERRCODE = 'TG202', HINT = format('SELECT tgsis.delete_geometry(%s) deletes the feature', p_geoid);
    END IF;
    IF p_timem <> v_first AND p_timem <> v_last THEN
        RAISE EXCEPTION 'the topology period from % of geometry % lies between others: removing it would leave a gap',
                p_timem, p_geoid
            USING ERRCODE = 'TG202',
                  DETAIL = format('Its periods start at %s; each ends where the next starts.',
                                  (SELECT string_agg(timem::text, ', ' ORDER BY timem) FROM tgsis.timem WHERE geoid = p_geoid)),
                  HINT = 'remove the first or the last period';
    END IF;
    FOR v_class IN SELECT * FROM tgsis.catalog WHERE timemodel = 'EVOLVING' LOOP
        EXECUTE format('DELETE FROM %I.%I WHERE _geoid = $1 AND _timem = $2', v_class.schemaname, v_class.cellprotable)
          USING p_geoid, p_timem;
        EXECUTE format('DELETE FROM %I.%I WHERE _geoid = $1 AND _timem = $2', v_class.schemaname, v_class.protablename)
          USING p_geoid, p_timem;
    END LOOP;
    DELETE FROM tgsis.d4dvrtx WHERE geoid = p_geoid AND timem = p_timem;
    DELETE FROM tgsis.d4dtrgl WHERE geoid = p_geoid AND timem = p_timem;
    DELETE FROM tgsis.node WHERE geoid = p_geoid AND timem = p_timem;
    DELETE FROM tgsis.timet WHERE geoid = p_geoid AND timem = p_timem;
    DELETE FROM tgsis.timem WHERE geoid = p_geoid AND timem = p_timem;
    PERFORM tgsis.refresh_geometry(p_geoid);
    RETURN true;
END
$$;

COMMENT ON FUNCTION tgsis.delete_period(bigint, double precision) IS
    'model 3: delete the first or last topology period (starting at timem) of an evolving surface with its nodes, triangles, positions and properties, in the session''s version; false if no period starts there; TG202 for the only period or one between others';

-- ==== model4/gmap_extent.sql ====
-- tgsis.gmap_extent(geoid): bounding box and counts of a G-map (model 4) over all its periods.
-- Model 4's extent function in the registry (tgsis.data_models), read by
-- tgsis.refresh_geometry. The box is of the first three coordinates (x, y, z;
-- 0 where the embedding has fewer), which holds every shape in between
-- (points move on straight lines); nvrtx counts nodes, ncell darts.
CREATE FUNCTION tgsis.gmap_extent(p_geoid bigint)
RETURNS TABLE (bbox cube, nvrtx bigint, ncell bigint)
LANGUAGE plpgsql
STABLE
SET search_path FROM CURRENT
AS $$
BEGIN
    SELECT count(*) INTO ncell FROM tgsis.gmap_dart d WHERE d.geoid = p_geoid;
    SELECT count(*) INTO nvrtx FROM tgsis.gmap_node n WHERE n.geoid = p_geoid;
    SELECT CASE WHEN count(*) > 0 THEN
                cube(ARRAY[min(coalesce(v.coordinate[1], 0)), min(coalesce(v.coordinate[2], 0)), min(coalesce(v.coordinate[3], 0))],
                     ARRAY[max(coalesce(v.coordinate[1], 0)), max(coalesce(v.coordinate[2], 0)), max(coalesce(v.coordinate[3], 0))])
           END
      INTO bbox
      FROM tgsis.gmap_vertex v WHERE v.geoid = p_geoid;
    RETURN NEXT;
END
$$;

COMMENT ON FUNCTION tgsis.gmap_extent(bigint) IS
    'bbox of the first three coordinates of every point at every geometry instant, number of nodes and of darts of a G-map (model 4) over all its periods; model 4''s extent function (tgsis.data_models)';

-- ==== model4/gmap_conditions.sql ====
-- tgsis.gmap_conditions(geoid, n, darts, alpha, node column): the conditions of an n-G-map over stored dart and alpha rows, with the offending darts.
-- Shared by the G-map models (model 4: tgsis.gmap_check over gmap_dart and
-- gmap_alpha; model 5: tgsis.md_check over md_dart and md_alpha), which add
-- their own (periods, points). Set-based: one keyed join per condition and
-- level. (i) every alpha_i is an involution; (ii) no dart is free in
-- alpha_i for i < n; (iii) alpha_i o alpha_j is an involution for
-- i + 2 <= j; the darts of one 0-cell share their point (alpha_1 .. alpha_n
-- keep it); the rows refer to what exists (a row per dart and level, images
-- that are darts). darts lists the first offending darts (at most 20).
-- The tables are given as regclass (quoted by their output), the point
-- column by name (%I): no caller text reaches the SQL unquoted.
CREATE FUNCTION tgsis.gmap_conditions(p_geoid bigint, p_n integer, p_dart regclass, p_alpha regclass, p_point text)
RETURNS TABLE (problem text, count bigint, darts bigint[])
LANGUAGE plpgsql
STABLE
SET search_path FROM CURRENT
AS $$
DECLARE
    v_i integer;
    v_j integer;
BEGIN
    RETURN QUERY EXECUTE format(
        'SELECT format(''dart has no alpha_%%s row'', l.level), count(*), (array_agg(d.dartid ORDER BY d.dartid))[1:20]
           FROM %1$s d CROSS JOIN generate_series(0, $2) AS l (level)
          WHERE d.geoid = $1
            AND NOT EXISTS (SELECT FROM %2$s a WHERE a.geoid = $1 AND a.level = l.level AND a.dartid = d.dartid)
          GROUP BY l.level ORDER BY l.level', p_dart, p_alpha) USING p_geoid, p_n;
    RETURN QUERY EXECUTE format(
        'SELECT CASE WHEN a.level > $2 THEN format(''alpha_%%s row above the dimension %%s'', a.level, $2)
                     ELSE format(''alpha_%%s row of a missing dart or to a missing dart'', a.level) END,
                count(*), (array_agg(a.dartid ORDER BY a.dartid))[1:20]
           FROM %2$s a
          WHERE a.geoid = $1
            AND (a.level > $2
                 OR NOT EXISTS (SELECT FROM %1$s d WHERE d.geoid = $1 AND d.dartid = a.dartid)
                 OR NOT EXISTS (SELECT FROM %1$s d WHERE d.geoid = $1 AND d.dartid = a.dartid2))
          GROUP BY a.level > $2, a.level ORDER BY a.level', p_dart, p_alpha) USING p_geoid, p_n;
    -- (i) and (ii)
    RETURN QUERY EXECUTE format(
        'SELECT format(''alpha_%%s is not an involution'', a.level), count(*), (array_agg(a.dartid ORDER BY a.dartid))[1:20]
           FROM %1$s a
           LEFT JOIN %1$s b ON b.geoid = a.geoid AND b.level = a.level AND b.dartid = a.dartid2
          WHERE a.geoid = $1 AND a.level <= $2 AND b.dartid2 IS DISTINCT FROM a.dartid
          GROUP BY a.level ORDER BY a.level', p_alpha) USING p_geoid, p_n;
    RETURN QUERY EXECUTE format(
        'SELECT format(''dart free in alpha_%%s (only alpha_%%s may have fixed points)'', a.level, $2), count(*),
                (array_agg(a.dartid ORDER BY a.dartid))[1:20]
           FROM %1$s a
          WHERE a.geoid = $1 AND a.level < $2 AND a.dartid2 = a.dartid
          GROUP BY a.level ORDER BY a.level', p_alpha) USING p_geoid, p_n;
    -- (iii): alpha_i(alpha_j(alpha_i(alpha_j(d)))) = d
    FOR v_i IN 0 .. p_n - 2 LOOP
        FOR v_j IN v_i + 2 .. p_n LOOP
            RETURN QUERY EXECUTE format(
                'SELECT format(''alpha_%%s o alpha_%%s is not an involution'', $2, $3), count(*),
                        (array_agg(j1.dartid ORDER BY j1.dartid))[1:20]
                   FROM %1$s j1
                   LEFT JOIN %1$s i1 ON i1.geoid = $1 AND i1.level = $2 AND i1.dartid = j1.dartid2
                   LEFT JOIN %1$s j2 ON j2.geoid = $1 AND j2.level = $3 AND j2.dartid = i1.dartid2
                   LEFT JOIN %1$s i2 ON i2.geoid = $1 AND i2.level = $2 AND i2.dartid = j2.dartid2
                  WHERE j1.geoid = $1 AND j1.level = $3 AND i2.dartid2 IS DISTINCT FROM j1.dartid
                 HAVING count(*) > 0', p_alpha) USING p_geoid, v_i, v_j;
        END LOOP;
    END LOOP;
    -- the darts of one 0-cell share their point
    RETURN QUERY EXECUTE format(
        'SELECT format(''alpha_%%s joins darts of different points (a 0-cell has one point)'', a.level), count(*),
                (array_agg(a.dartid ORDER BY a.dartid))[1:20]
           FROM %2$s a
           JOIN %1$s d ON d.geoid = a.geoid AND d.dartid = a.dartid
           JOIN %1$s e ON e.geoid = a.geoid AND e.dartid = a.dartid2
          WHERE a.geoid = $1 AND a.level >= 1 AND d.%3$I <> e.%3$I
          GROUP BY a.level ORDER BY a.level', p_dart, p_alpha, p_point) USING p_geoid;
END
$$;

COMMENT ON FUNCTION tgsis.gmap_conditions(bigint, integer, regclass, regclass, text) IS
    'the conditions of an n-G-map over stored dart and alpha rows (missing or dangling alpha rows, (i) involutions, (ii) no fixed point below alpha_n, (iii) alpha_i o alpha_j involutions for i + 2 <= j, one point per 0-cell) with the first offending darts; shared by tgsis.gmap_check (model 4) and tgsis.md_check (model 5)';

-- ==== model4/gmap_check.sql ====
-- tgsis.gmap_check(geoid): the conditions of an n-G-map and of its periods, with the offending darts (no rows: valid).
-- The conditions every G-map model shares (tgsis.gmap_conditions: (i)-(iii),
-- one point per 0-cell, rows that refer to darts), and model 4's own: every
-- involution keeps a dart in its topology period (the closure of the
-- partition D0..Dk), darts of nodes and periods that exist. darts lists the
-- first offending darts (at most 20), count all of them.
CREATE FUNCTION tgsis.gmap_check(p_geoid bigint)
RETURNS TABLE (problem text, count bigint, darts bigint[])
LANGUAGE plpgsql
STABLE
SET search_path FROM CURRENT
AS $$
DECLARE
    v_n smallint;
BEGIN
    SELECT g.dimension INTO v_n FROM tgsis.gmap g WHERE g.geoid = p_geoid;
    IF NOT FOUND THEN
        RAISE EXCEPTION 'geometry % is not a stored G-map', p_geoid
            USING ERRCODE = 'TG200', HINT = 'SELECT geoid FROM tgsis.gmap lists the stored G-maps';
    END IF;
    RETURN QUERY SELECT * FROM tgsis.gmap_conditions(p_geoid, v_n, 'tgsis.gmap_dart', 'tgsis.gmap_alpha', 'nodeid');
    -- the partition into periods, the shared nodes of 0-cells, nodes of the dart's period
    RETURN QUERY
        SELECT format('alpha_%s sends a dart into another topology period', a.level), count(*),
               (array_agg(a.dartid ORDER BY a.dartid))[1:20]
          FROM tgsis.gmap_alpha a
          JOIN tgsis.gmap_dart d ON d.geoid = a.geoid AND d.dartid = a.dartid
          JOIN tgsis.gmap_dart e ON e.geoid = a.geoid AND e.dartid = a.dartid2
         WHERE a.geoid = p_geoid AND d.timem <> e.timem
         GROUP BY a.level ORDER BY a.level;
    RETURN QUERY
        SELECT 'dart of a node missing from its topology period'::text, count(*), (array_agg(d.dartid ORDER BY d.dartid))[1:20]
          FROM tgsis.gmap_dart d
         WHERE d.geoid = p_geoid
           AND NOT EXISTS (SELECT FROM tgsis.gmap_node n WHERE n.geoid = p_geoid AND n.timem = d.timem AND n.nodeid = d.nodeid)
        HAVING count(*) > 0;
    RETURN QUERY
        SELECT 'dart of a topology period that does not exist'::text, count(*), (array_agg(d.dartid ORDER BY d.dartid))[1:20]
          FROM tgsis.gmap_dart d
         WHERE d.geoid = p_geoid
           AND NOT EXISTS (SELECT FROM tgsis.gmap_timem m WHERE m.geoid = p_geoid AND m.timem = d.timem)
        HAVING count(*) > 0;
END
$$;

COMMENT ON FUNCTION tgsis.gmap_check(bigint) IS
    'problems of a stored G-map (model 4) with the first offending darts: missing or dangling alpha rows, (i) non-involutions, (ii) fixed points below alpha_n, (iii) alpha_i o alpha_j not involutions (i + 2 <= j), darts sent into another topology period, 0-cells with several nodes, darts of missing nodes or periods; no rows: valid';

-- ==== model4/check_gmap_geometry.sql ====
-- tgsis.check_gmap_geometry(geoid): what is wrong with a stored G-map geometry, in the form tgsis.check_geometry returns.
-- Model 4's check function in the registry (tgsis.data_models): the
-- conditions of tgsis.gmap_check (first offending dart as the example), the
-- positions of every node at every geometry instant of its period with m
-- coordinates, and the bbox and counts.
CREATE FUNCTION tgsis.check_gmap_geometry(p_geoid bigint)
RETURNS TABLE (problem text, count bigint, example text)
LANGUAGE plpgsql
STABLE
SET search_path FROM CURRENT
AS $$
DECLARE
    v_m smallint;
BEGIN
    IF NOT EXISTS (SELECT FROM tgsis.gmap g WHERE g.geoid = p_geoid) THEN
        RETURN QUERY SELECT 'G-map geometry has no tgsis.gmap row'::text, 1::bigint, p_geoid::text;
        RETURN;
    END IF;
    RETURN QUERY SELECT c.problem, c.count, 'dart ' || c.darts[1] FROM tgsis.gmap_check(p_geoid) c;
    SELECT g.embedding INTO v_m FROM tgsis.gmap g WHERE g.geoid = p_geoid;
    RETURN QUERY
        SELECT format('point without %s finite coordinates', v_m), count(*), 'node ' || min(v.nodeid)
          FROM tgsis.gmap_vertex v
         WHERE v.geoid = p_geoid
           AND (cardinality(v.coordinate) <> v_m
                OR EXISTS (SELECT FROM unnest(v.coordinate) c WHERE c IN ('NaN', 'Infinity', '-Infinity')))
        HAVING count(*) > 0;
    RETURN QUERY
        SELECT 'node without a position at a geometry instant of its period'::text, count(*), 'node ' || min(n.nodeid)
          FROM tgsis.gmap_node n
          JOIN tgsis.gmap_timet t ON t.geoid = n.geoid AND t.timem = n.timem
         WHERE n.geoid = p_geoid
           AND NOT EXISTS (SELECT FROM tgsis.gmap_vertex v WHERE v.geoid = n.geoid AND v.timem = n.timem
                                                            AND v.timet = t.timet AND v.nodeid = n.nodeid)
        HAVING count(*) > 0;
    RETURN QUERY
        SELECT 'bounding box or counts out of date (run tgsis.refresh_geometry)'::text, 1::bigint, NULL::text
          FROM tgsis.geometry g, tgsis.gmap_extent(p_geoid) e
         WHERE g.geoid = p_geoid
           AND (g.nvrtx <> e.nvrtx OR g.ncell <> e.ncell OR g.bbox IS DISTINCT FROM e.bbox);
END
$$;

COMMENT ON FUNCTION tgsis.check_gmap_geometry(bigint) IS
    'problems of a stored G-map geometry: those of tgsis.gmap_check, points without m finite coordinates, nodes missing a position at an instant of their period, stale bbox/counts; model 4''s check function (tgsis.data_models)';

-- ==== model4/gmap_frame.sql ====
-- tgsis.gmap_frame(geoid, t): where t falls in a G-map (model 4): its topology period, the bracketing geometry instants t0 <= t <= t1 and the weight w = (t - t0) / (t1 - t0).
-- The rules of model 3 (tgsis.evolving_frame, tgsis.temporal.frame_at): the
-- period is the last topology instant <= t; no row before the first instant,
-- nor after the last geometry instant unless the geometry is alive (then
-- t0 = t1 = the last, w = 0).
CREATE FUNCTION tgsis.gmap_frame(p_geoid bigint, p_t double precision)
RETURNS TABLE (timem double precision, t0 double precision, t1 double precision, w double precision)
LANGUAGE plpgsql
STABLE
SET search_path FROM CURRENT
AS $$
BEGIN
    -- (PL/pgSQL: the model-4 tables do not exist yet when the extension script runs)
    RETURN QUERY
    WITH period AS (
        SELECT m.timem,
               NOT EXISTS (SELECT FROM tgsis.gmap_timem n WHERE n.geoid = p_geoid AND n.timem > m.timem) AS last
          FROM tgsis.gmap_timem m
         WHERE m.geoid = p_geoid AND m.timem <= tgsis.checked_time(p_t)
         ORDER BY m.timem DESC
         LIMIT 1
    ), bracket AS (
        SELECT p.timem, p.last,
               (SELECT max(i.timet) FROM tgsis.gmap_timet i WHERE i.geoid = p_geoid AND i.timem = p.timem AND i.timet <= p_t) AS lo,
               (SELECT min(i.timet) FROM tgsis.gmap_timet i WHERE i.geoid = p_geoid AND i.timem = p.timem AND i.timet >= p_t) AS hi
          FROM period p
    )
    SELECT b.timem, b.lo, coalesce(b.hi, b.lo),
           CASE WHEN b.hi IS NULL OR b.hi = b.lo THEN 0::double precision ELSE (p_t - b.lo) / (b.hi - b.lo) END
      FROM bracket b
      JOIN tgsis.geometry g ON g.geoid = p_geoid
     WHERE b.lo IS NOT NULL
       AND (b.hi IS NOT NULL OR g.alive OR NOT b.last);
END
$$;

COMMENT ON FUNCTION tgsis.gmap_frame(bigint, double precision) IS
    'model 4: topology period (timem) and bracketing geometry instants t0 <= t <= t1 of a G-map at t, with w = (t - t0)/(t1 - t0); no row when it does not exist at t';

-- ==== model4/gmap_at.sql ====
-- tgsis.gmap_at(geoid, t): the darts of a G-map at model time t, each with its node and its images under alpha_0 .. alpha_n.
-- The snapshot's topology: the darts (with the cell of the property level each is in) of the topology period containing t
-- (tgsis.gmap_frame); none before the first instant, nor after the end
-- unless alive. The points are tgsis.gmap_points_at, the property values
-- tgsis.gmap_property_at (same t, same period).
CREATE FUNCTION tgsis.gmap_at(p_geoid bigint, p_t double precision)
RETURNS TABLE (dartid bigint, nodeid bigint, acellid bigint, alpha bigint[])
LANGUAGE plpgsql
STABLE
SET search_path FROM CURRENT
AS $$
BEGIN
    -- one keyed probe of gmap_alpha (geoid, dartid, level) per dart: the same plan whatever the statistics
    -- say (a join planned on a freshly loaded, not yet analysed table can scan the geometry's rows per dart)
    RETURN QUERY
    SELECT d.dartid, d.nodeid, d.acellid,
           ARRAY(SELECT a.dartid2 FROM tgsis.gmap_alpha a WHERE a.geoid = p_geoid AND a.dartid = d.dartid ORDER BY a.level)
      FROM tgsis.gmap_frame(p_geoid, p_t) f
      JOIN tgsis.gmap_dart d ON d.geoid = p_geoid AND d.timem = f.timem
     ORDER BY d.dartid;
END
$$;

COMMENT ON FUNCTION tgsis.gmap_at(bigint, double precision) IS
    'model 4 snapshot at t: the darts of the topology period containing t with their node, their cell of the class''s property level (acellid) and {alpha_0(d), ..., alpha_n(d)}, by dartid; none when the G-map does not exist at t';

-- ==== model4/gmap_points_at.sql ====
-- tgsis.gmap_points_at(geoid, t): the points of a G-map's nodes at model time t, interpolated between the bracketing geometry instants.
-- Each coordinate is a + w (b - a) between the positions at t0 and t1 of the
-- period containing t (tgsis.gmap_frame), the formula EvolvingGMap.at uses
-- (equal to the bit); the positions at t0 when t is an instant.
CREATE FUNCTION tgsis.gmap_points_at(p_geoid bigint, p_t double precision)
RETURNS TABLE (nodeid bigint, coordinate double precision[])
LANGUAGE plpgsql
STABLE
SET search_path FROM CURRENT
AS $$
BEGIN
    RETURN QUERY
    SELECT a.nodeid,
           CASE WHEN f.t0 = f.t1 THEN a.coordinate
                ELSE ARRAY(SELECT x + f.w * (y - x) FROM unnest(a.coordinate, b.coordinate) WITH ORDINALITY AS u (x, y, i)
                            ORDER BY u.i) END
      FROM tgsis.gmap_frame(p_geoid, p_t) f
      JOIN tgsis.gmap_vertex a ON a.geoid = p_geoid AND a.timem = f.timem AND a.timet = f.t0
      JOIN tgsis.gmap_vertex b ON b.geoid = p_geoid AND b.timem = f.timem AND b.timet = f.t1 AND b.nodeid = a.nodeid
     ORDER BY a.nodeid;
END
$$;

COMMENT ON FUNCTION tgsis.gmap_points_at(bigint, double precision) IS
    'model 4 snapshot at t: every node of the period containing t with its point interpolated linearly between the bracketing geometry instants, by nodeid; none when the G-map does not exist at t';

-- ==== model4/cell_labels.sql ====
-- tgsis.cell_labels(geoid, level, darts, alpha, period): the level-cells of stored G-map rows: for each dart, its cell.
-- Shared by tgsis.gmap_cells (model 4, the darts of one topology period) and
-- tgsis.md_cells (model 5, every dart). An i-cell is an orbit of every
-- involution but alpha_i. Set-based over the darts: every dart starts
-- labelled by itself, then each round takes the least label among its
-- images (one keyed join for all darts) and jumps to its label's label,
-- until nothing changes; the label is then the orbit's least dart (rounds
-- grow with the logarithm of the orbit's diameter, not with the number of
-- darts). cell numbers the cells 0, 1, ... in the order of their least dart,
-- as tgsis.gmaps.GMap.cells does. VOLATILE: the work table is temporary.
-- The tables are regclass (quoted by their output): no caller text reaches the SQL.
CREATE FUNCTION tgsis.cell_labels(p_geoid bigint, p_level integer, p_dart regclass, p_alpha regclass,
                                  p_timem double precision DEFAULT NULL)
RETURNS TABLE (dartid bigint, cell bigint, firstdart bigint)
LANGUAGE plpgsql
VOLATILE
SET search_path FROM CURRENT
AS $$
DECLARE
    v_changed bigint;
BEGIN
    DROP TABLE IF EXISTS pg_temp.tgsis_cell_labels;
    CREATE TEMPORARY TABLE tgsis_cell_labels (dartid bigint PRIMARY KEY, label bigint NOT NULL) ON COMMIT DROP;
    EXECUTE format('INSERT INTO pg_temp.tgsis_cell_labels SELECT d.dartid, d.dartid FROM %s d WHERE d.geoid = $1 %s',
                   p_dart, CASE WHEN p_timem IS NOT NULL THEN 'AND d.timem = $2' ELSE '' END)
        USING p_geoid, p_timem;
    ANALYZE pg_temp.tgsis_cell_labels;
    LOOP
        EXECUTE format(
            'UPDATE pg_temp.tgsis_cell_labels w SET label = m.label
               FROM (SELECT a.dartid, min(o.label) AS label
                       FROM %s a
                       JOIN pg_temp.tgsis_cell_labels o ON o.dartid = a.dartid2
                      WHERE a.geoid = $1 AND a.level <> $2
                        AND a.dartid IN (SELECT c.dartid FROM pg_temp.tgsis_cell_labels c)
                      GROUP BY a.dartid) m
              WHERE w.dartid = m.dartid AND m.label < w.label', p_alpha) USING p_geoid, p_level;
        GET DIAGNOSTICS v_changed = ROW_COUNT;
        EXIT WHEN v_changed = 0;
        UPDATE pg_temp.tgsis_cell_labels w SET label = o.label
          FROM pg_temp.tgsis_cell_labels o
         WHERE o.dartid = w.label AND o.label < w.label;
    END LOOP;
    RETURN QUERY
    SELECT w.dartid, dense_rank() OVER (ORDER BY w.label) - 1, w.label
      FROM pg_temp.tgsis_cell_labels w
     ORDER BY w.dartid;
    DROP TABLE pg_temp.tgsis_cell_labels;
END
$$;

COMMENT ON FUNCTION tgsis.cell_labels(bigint, integer, regclass, regclass, double precision) IS
    'the level-cells (orbits of every involution but alpha_level) of a stored G-map''s darts (those of one topology period when timem is given): each dart with its cell number (0.. by least dart, as GMap.cells) and the cell''s least dart; shared by tgsis.gmap_cells and tgsis.md_cells';

-- ==== model4/gmap_cells.sql ====
-- tgsis.gmap_cells(geoid, level, t): the i-cells of a G-map at model time t: for each dart of the period, its cell.
-- An i-cell is an orbit of every involution but alpha_i, computed set-based
-- over the darts of the topology period containing t (tgsis.cell_labels);
-- cell numbers the cells 0, 1, ... in the order of their least dart, as
-- tgsis.gmaps.GMap.cells does for the snapshot. VOLATILE: tgsis.cell_labels
-- works in a temporary table.
CREATE FUNCTION tgsis.gmap_cells(p_geoid bigint, p_level integer, p_t double precision)
RETURNS TABLE (dartid bigint, cell bigint, firstdart bigint)
LANGUAGE plpgsql
VOLATILE
SET search_path FROM CURRENT
AS $$
DECLARE
    v_n       smallint;
    v_timem   double precision;
BEGIN
    SELECT g.dimension INTO v_n FROM tgsis.gmap g WHERE g.geoid = p_geoid;
    IF NOT FOUND THEN
        RAISE EXCEPTION 'geometry % is not a stored G-map', p_geoid
            USING ERRCODE = 'TG200', HINT = 'SELECT geoid FROM tgsis.gmap lists the stored G-maps';
    END IF;
    IF p_level IS NULL OR p_level < 0 OR p_level > v_n THEN
        RAISE EXCEPTION 'cell level % is not a cell dimension of the %-G-map %', coalesce(p_level::text, 'NULL'), v_n, p_geoid
            USING ERRCODE = 'TG100', HINT = format('p_level => 0 .. %s', v_n);
    END IF;
    SELECT f.timem INTO v_timem FROM tgsis.gmap_frame(p_geoid, p_t) f;
    IF NOT FOUND THEN
        RETURN;  -- it does not exist at t
    END IF;
    RETURN QUERY SELECT * FROM tgsis.cell_labels(p_geoid, p_level, 'tgsis.gmap_dart', 'tgsis.gmap_alpha', v_timem);
END
$$;

COMMENT ON FUNCTION tgsis.gmap_cells(bigint, integer, double precision) IS
    'model 4: the level-cells (orbits of every involution but alpha_level) of the G-map at t: each dart of the period with its cell number (0.. in the order of the cells'' least darts, as GMap.cells) and the cell''s least dart; none when it does not exist at t';

-- ==== model4/gmap_property_at.sql ====
-- tgsis.gmap_property_at(class, geoid, property, t): the values of a numeric cell property of a G-map feature at model time t.
-- The class's property level's cells of the period containing t (acellid,
-- the _idx of the class's property table), each value linear between the
-- bracketing geometry instants, a + w (b - a), as EvolvingGMap.at computes
-- it; no rows when the feature does not exist at t; NULL values stay NULL.
CREATE FUNCTION tgsis.gmap_property_at(p_class text, p_geoid bigint, p_property text, p_t double precision)
RETURNS TABLE (acellid bigint, value double precision)
LANGUAGE plpgsql
STABLE
AS $$
DECLARE
    v_class tgsis.catalog := tgsis.catalog_row(p_class);
    v_found integer;
BEGIN
    IF v_class.celllevel IS NULL THEN
        RAISE EXCEPTION 'feature class % is not a class of G-maps', p_class
            USING ERRCODE = 'TG100', HINT = 'tgsis.property_at gives the property values of models 1 to 3';
    END IF;
    IF NOT EXISTS (SELECT FROM jsonb_array_elements(v_class.cell_properties) p
                    WHERE p ->> 'name' = p_property AND NOT p ? 'size'
                      AND p ->> 'type' IN ('smallint', 'integer', 'bigint', 'real', 'double precision', 'numeric')) THEN
        RAISE EXCEPTION 'feature class % has no numeric scalar cell property %', p_class, coalesce(quote_literal(p_property), 'NULL')
            USING ERRCODE = 'TG103',
                  HINT = format('its cell properties: %s',
                                coalesce((SELECT string_agg(p ->> 'name', ', ') FROM jsonb_array_elements(v_class.cell_properties) p),
                                         'none'));
    END IF;
    EXECUTE format('SELECT 1 FROM %I.%I WHERE _geoid = $1', v_class.schemaname, v_class.featuretable) INTO v_found USING p_geoid;
    IF v_found IS NULL THEN
        RAISE EXCEPTION 'feature class % has no feature %', p_class, p_geoid USING ERRCODE = 'TG200';
    END IF;
    PERFORM tgsis.checked_time(p_t);
    RETURN QUERY EXECUTE format(
        'WITH f AS MATERIALIZED (SELECT * FROM tgsis.gmap_frame($1, $2))
         SELECT a._idx, CASE WHEN (SELECT f.t0 = f.t1 FROM f) THEN a.%1$I::double precision
                             ELSE a.%1$I::double precision
                                  + (SELECT f.w FROM f) * (b.%1$I::double precision - a.%1$I::double precision) END
           FROM %2$I.%3$I a
           JOIN %2$I.%3$I b ON b._geoid = a._geoid AND b._timem = a._timem AND b._idx = a._idx
          WHERE a._geoid = $1 AND a._timem = (SELECT f.timem FROM f) AND a._timet = (SELECT f.t0 FROM f)
            AND b._timet = (SELECT f.t1 FROM f)
          ORDER BY a._idx',
        p_property, v_class.schemaname, v_class.cellprotable) USING p_geoid, p_t;
END
$$;

COMMENT ON FUNCTION tgsis.gmap_property_at(text, bigint, text, double precision) IS
    'model 4: values (acellid, value) of a numeric cell property of a G-map feature at t, linear between the bracketing geometry instants of the period containing t; none when the feature does not exist at t';

-- ==== model5/md_extent.sql ====
-- tgsis.md_extent(geoid): bounding box and counts of a multiply indexed G-map (model 5).
-- Model 5's extent function in the registry (tgsis.data_models), read by
-- tgsis.refresh_geometry: the 3D box of tgsis.geometry is of the first
-- three axes (0 where there are fewer); nvrtx counts points, ncell darts.
-- It also brings tgsis.md_gmap.extent (every axis) up to date.
CREATE FUNCTION tgsis.md_extent(p_geoid bigint)
RETURNS TABLE (bbox cube, nvrtx bigint, ncell bigint)
LANGUAGE plpgsql
VOLATILE
SET search_path FROM CURRENT
AS $$
BEGIN
    SELECT count(*) INTO ncell FROM tgsis.md_dart d WHERE d.geoid = p_geoid;
    SELECT count(*),
           CASE WHEN count(*) > 0 THEN
                cube(ARRAY[min(coalesce(v.coordinate[1], 0)), min(coalesce(v.coordinate[2], 0)), min(coalesce(v.coordinate[3], 0))],
                     ARRAY[max(coalesce(v.coordinate[1], 0)), max(coalesce(v.coordinate[2], 0)), max(coalesce(v.coordinate[3], 0))])
           END
      INTO nvrtx, bbox
      FROM tgsis.md_vertex v WHERE v.geoid = p_geoid;
    UPDATE tgsis.md_gmap g SET extent = e.extent
      FROM (SELECT CASE WHEN count(*) > 0 THEN cube(array_agg(lo ORDER BY i), array_agg(hi ORDER BY i)) END AS extent
              FROM (SELECT u.i, min(u.x) AS lo, max(u.x) AS hi
                      FROM tgsis.md_vertex v, unnest(v.coordinate) WITH ORDINALITY AS u (x, i)
                     WHERE v.geoid = p_geoid GROUP BY u.i) a) e
     WHERE g.geoid = p_geoid AND g.extent IS DISTINCT FROM e.extent;
    RETURN NEXT;
END
$$;

COMMENT ON FUNCTION tgsis.md_extent(bigint) IS
    'bbox of the first three axes, number of points and of darts of a multiply indexed G-map (model 5), and its extent over every axis (tgsis.md_gmap.extent) brought up to date; model 5''s extent function (tgsis.data_models)';

-- ==== model5/md_check.sql ====
-- tgsis.md_check(geoid): the conditions of a stored multiply indexed G-map (model 5), with the offending darts (no rows: valid).
-- The conditions every G-map model shares (tgsis.gmap_conditions: (i)-(iii),
-- one point per 0-cell, rows that refer to darts) and model 5's own: darts
-- of points that exist.
CREATE FUNCTION tgsis.md_check(p_geoid bigint)
RETURNS TABLE (problem text, count bigint, darts bigint[])
LANGUAGE plpgsql
STABLE
SET search_path FROM CURRENT
AS $$
DECLARE
    v_n smallint;
BEGIN
    SELECT g.dimension INTO v_n FROM tgsis.md_gmap g WHERE g.geoid = p_geoid;
    IF NOT FOUND THEN
        RAISE EXCEPTION 'geometry % is not a stored multiply indexed G-map', p_geoid
            USING ERRCODE = 'TG200', HINT = 'SELECT geoid FROM tgsis.md_gmap lists them';
    END IF;
    RETURN QUERY SELECT * FROM tgsis.gmap_conditions(p_geoid, v_n, 'tgsis.md_dart', 'tgsis.md_alpha', 'vrtxid');
    RETURN QUERY
        SELECT 'dart of a point that does not exist'::text, count(*), (array_agg(d.dartid ORDER BY d.dartid))[1:20]
          FROM tgsis.md_dart d
         WHERE d.geoid = p_geoid
           AND NOT EXISTS (SELECT FROM tgsis.md_vertex v WHERE v.geoid = p_geoid AND v.vrtxid = d.vrtxid)
        HAVING count(*) > 0;
END
$$;

COMMENT ON FUNCTION tgsis.md_check(bigint) IS
    'problems of a stored multiply indexed G-map (model 5) with the first offending darts: those of tgsis.gmap_conditions and darts of missing points; no rows: valid';

-- ==== model5/check_md_geometry.sql ====
-- tgsis.check_md_geometry(geoid): what is wrong with a stored multiply indexed G-map, in the form tgsis.check_geometry returns.
-- Model 5's check function in the registry (tgsis.data_models): the
-- conditions of tgsis.md_check (first offending dart as the example), points
-- without m finite coordinates, a stale extent, bbox or counts.
CREATE FUNCTION tgsis.check_md_geometry(p_geoid bigint)
RETURNS TABLE (problem text, count bigint, example text)
LANGUAGE plpgsql
STABLE
SET search_path FROM CURRENT
AS $$
DECLARE
    v_m smallint;
BEGIN
    SELECT g.embedding INTO v_m FROM tgsis.md_gmap g WHERE g.geoid = p_geoid;
    IF NOT FOUND THEN
        RETURN QUERY SELECT 'multiply indexed G-map geometry has no tgsis.md_gmap row'::text, 1::bigint, p_geoid::text;
        RETURN;
    END IF;
    RETURN QUERY SELECT c.problem, c.count, 'dart ' || c.darts[1] FROM tgsis.md_check(p_geoid) c;
    RETURN QUERY
        SELECT format('point without %s finite coordinates', v_m), count(*), 'vertex ' || min(v.vrtxid)
          FROM tgsis.md_vertex v
         WHERE v.geoid = p_geoid
           AND (cardinality(v.coordinate) <> v_m
                OR EXISTS (SELECT FROM unnest(v.coordinate) c WHERE c IN ('NaN', 'Infinity', '-Infinity')))
        HAVING count(*) > 0;
    RETURN QUERY
        SELECT 'extent, bounding box or counts out of date (run tgsis.refresh_geometry)'::text, 1::bigint, NULL::text
          FROM tgsis.geometry g
          JOIN tgsis.md_gmap m ON m.geoid = g.geoid
          CROSS JOIN LATERAL (SELECT count(*) AS n,
                                     CASE WHEN count(*) > 0 THEN
                                         cube(ARRAY[min(coalesce(v.coordinate[1], 0)), min(coalesce(v.coordinate[2], 0)),
                                                    min(coalesce(v.coordinate[3], 0))],
                                              ARRAY[max(coalesce(v.coordinate[1], 0)), max(coalesce(v.coordinate[2], 0)),
                                                    max(coalesce(v.coordinate[3], 0))]) END AS bbox,
                                     bool_and(m.extent IS NOT NULL AND cube(v.coordinate) <@ m.extent) AS inside
                                FROM tgsis.md_vertex v WHERE v.geoid = p_geoid) s
         WHERE g.geoid = p_geoid
           AND (g.nvrtx <> s.n OR g.bbox IS DISTINCT FROM s.bbox OR NOT coalesce(s.inside, m.extent IS NULL)
                OR g.ncell <> (SELECT count(*) FROM tgsis.md_dart d WHERE d.geoid = p_geoid));
END
$$;

COMMENT ON FUNCTION tgsis.check_md_geometry(bigint) IS
    'problems of a stored multiply indexed G-map geometry: those of tgsis.md_check, points without m finite coordinates, a stale extent, bbox or counts; model 5''s check function (tgsis.data_models)';

-- ==== model5/md_cells.sql ====
-- tgsis.md_cells(geoid, level): the level-cells of a multiply indexed G-map (model 5): for each dart, its cell.
-- Orbits of every involution but alpha_level, set-based (tgsis.cell_labels);
-- cell numbers the cells 0, 1, ... in the order of their least dart, as
-- tgsis.gmaps.GMap.cells. VOLATILE: tgsis.cell_labels works in a temporary table.
CREATE FUNCTION tgsis.md_cells(p_geoid bigint, p_level integer)
RETURNS TABLE (dartid bigint, cell bigint, firstdart bigint)
LANGUAGE plpgsql
VOLATILE
SET search_path FROM CURRENT
AS $$
DECLARE
    v_n smallint;
BEGIN
    SELECT g.dimension INTO v_n FROM tgsis.md_gmap g WHERE g.geoid = p_geoid;
    IF NOT FOUND THEN
        RAISE EXCEPTION 'geometry % is not a stored multiply indexed G-map', p_geoid
            USING ERRCODE = 'TG200', HINT = 'SELECT geoid FROM tgsis.md_gmap lists them';
    END IF;
    IF p_level IS NULL OR p_level < 0 OR p_level > v_n THEN
        RAISE EXCEPTION 'cell level % is not a cell dimension of the %-G-map %', coalesce(p_level::text, 'NULL'), v_n, p_geoid
            USING ERRCODE = 'TG100', HINT = format('p_level => 0 .. %s', v_n);
    END IF;
    RETURN QUERY SELECT * FROM tgsis.cell_labels(p_geoid, p_level, 'tgsis.md_dart', 'tgsis.md_alpha');
END
$$;

COMMENT ON FUNCTION tgsis.md_cells(bigint, integer) IS
    'model 5: the level-cells of a multiply indexed G-map: each dart with its cell number (0.. in the order of the cells'' least darts, as GMap.cells) and the cell''s least dart';

-- ==== model5/md_query_box.sql ====
-- tgsis.md_query_box(axes of the object, axes asked, low, high): the m-dimensional cube of a box over some of an object's axes.
-- A box over a subset of the dimensions is the cube that is unbounded
-- (-Infinity .. Infinity) on every other axis, so that one GiST index on the
-- full extents (or points) serves a query over any subset. NULL when the
-- object lacks one of the asked axes (it cannot be in the box).
CREATE FUNCTION tgsis.md_query_box(p_object_axes text[], p_axes text[], p_low double precision[],
                                   p_high double precision[])
RETURNS cube
LANGUAGE plpgsql
IMMUTABLE
PARALLEL SAFE
SET search_path FROM CURRENT
AS $$
DECLARE
    v_low  double precision[] := array_fill('-Infinity'::double precision, ARRAY[cardinality(p_object_axes)]);
    v_high double precision[] := array_fill('Infinity'::double precision, ARRAY[cardinality(p_object_axes)]);
    v_at   integer;
BEGIN
    IF p_axes IS NULL OR cardinality(p_axes) = 0 OR cardinality(p_low) IS DISTINCT FROM cardinality(p_axes)
       OR cardinality(p_high) IS DISTINCT FROM cardinality(p_axes) THEN
        RAISE EXCEPTION 'a box names at least one axis and gives one low and one high value per axis, got axes %, low %, high %',
                        p_axes, p_low, p_high
            USING ERRCODE = 'TG100', HINT = 'p_axes => ''{x,knowledge}'', p_low => ''{0,1}'', p_high => ''{10,2}''';
    END IF;
    FOR i IN 1 .. cardinality(p_axes) LOOP
        IF p_low[i] IS NULL OR p_high[i] IS NULL OR p_low[i] = 'NaN' OR p_high[i] = 'NaN' OR p_low[i] > p_high[i] THEN
            RAISE EXCEPTION 'the box over axis % must have low <= high, got % .. %', quote_literal(p_axes[i]), p_low[i], p_high[i]
                USING ERRCODE = 'TG100';
        END IF;
        v_at := array_position(p_object_axes, p_axes[i]);
        IF v_at IS NULL THEN
            RETURN NULL;
        END IF;
        v_low[v_at] := greatest(v_low[v_at], p_low[i]);
        v_high[v_at] := least(v_high[v_at], p_high[i]);
    END LOOP;
    RETURN cube(v_low, v_high);
END
$$;

COMMENT ON FUNCTION tgsis.md_query_box(text[], text[], double precision[], double precision[]) IS
    'model 5: the cube over an object''s axes of a box given on some of them (unbounded on the others); NULL when the object lacks an asked axis; TG100 for a malformed box';

-- ==== model5/md_in_box.sql ====
-- tgsis.md_in_box(class, axes, low, high): the multiply indexed G-map features of a class whose extent meets a box over some of their axes.
-- E.g. the interpretations of a horizon that reach x in [0, 100] at knowledge
-- level 2: p_axes => '{x,knowledge}'. One GiST index scan (md_gmap_extent_idx)
-- per set of axes among the class's features (features may name their axes
-- differently; those lacking an asked axis are not in the box).
CREATE FUNCTION tgsis.md_in_box(p_class text, p_axes text[], p_low double precision[], p_high double precision[])
RETURNS SETOF bigint
LANGUAGE plpgsql
STABLE
AS $$
DECLARE
    v_class tgsis.catalog := tgsis.catalog_row(p_class);
    v_axes  text[];
BEGIN
    IF v_class.timemodel IS DISTINCT FROM 'MULTIDIM' THEN
        RAISE EXCEPTION 'feature class % holds % features, not multiply indexed G-maps', p_class, v_class.timemodel
            USING ERRCODE = 'TG100', HINT = 'tgsis.geometries_in_box finds features of the other models by their 3D box';
    END IF;
    PERFORM tgsis.md_query_box(ARRAY[]::text[] || p_axes, p_axes, p_low, p_high);  -- a malformed box is an error even for an empty class
    FOR v_axes IN EXECUTE format('SELECT DISTINCT m.axes FROM %I.%I f JOIN tgsis.md_gmap m ON m.geoid = f._geoid',
                                 v_class.schemaname, v_class.featuretable) LOOP
        RETURN QUERY EXECUTE format(
            'SELECT f._geoid FROM %I.%I f JOIN tgsis.md_gmap m ON m.geoid = f._geoid
              WHERE m.axes = $1 AND m.extent && tgsis.md_query_box($1, $2, $3, $4) ORDER BY f._geoid',
            v_class.schemaname, v_class.featuretable) USING v_axes, p_axes, p_low, p_high;
    END LOOP;
END
$$;

COMMENT ON FUNCTION tgsis.md_in_box(text, text[], double precision[], double precision[]) IS
    'model 5: ids of the features of a class of multiply indexed G-maps whose extent meets a box over some of their axes (unbounded on the others), by GiST index';

-- ==== model5/md_vertices_in_box.sql ====
-- tgsis.md_vertices_in_box(geoid, axes, low, high): the points of a multiply indexed G-map inside a box over some of its axes.
-- E.g. the part of a horizon's interpretations between knowledge 1 and 2
-- over an x-y window. The points are GiST-indexed as cubes
-- (md_vertex_point_idx); the box is unbounded on the axes not given.
CREATE FUNCTION tgsis.md_vertices_in_box(p_geoid bigint, p_axes text[], p_low double precision[], p_high double precision[])
RETURNS TABLE (vrtxid bigint, coordinate double precision[])
LANGUAGE plpgsql
STABLE
SET search_path FROM CURRENT
AS $$
DECLARE
    v_box cube;
BEGIN
    SELECT tgsis.md_query_box(g.axes, p_axes, p_low, p_high) INTO v_box FROM tgsis.md_gmap g WHERE g.geoid = p_geoid;
    IF NOT FOUND THEN
        RAISE EXCEPTION 'geometry % is not a stored multiply indexed G-map', p_geoid
            USING ERRCODE = 'TG200', HINT = 'SELECT geoid FROM tgsis.md_gmap lists them';
    END IF;
    RETURN QUERY
    SELECT v.vrtxid, v.coordinate FROM tgsis.md_vertex v
     WHERE cube(v.coordinate) <@ v_box AND v.geoid = p_geoid
     ORDER BY v.vrtxid;
END
$$;

COMMENT ON FUNCTION tgsis.md_vertices_in_box(bigint, text[], double precision[], double precision[]) IS
    'model 5: the points (vrtxid, coordinate) of a multiply indexed G-map inside a box over some of its axes (unbounded on the others), by GiST index';

-- ==== postgis/postgis_schema.sql ====
-- tgsis.postgis_schema(): the schema PostGIS is installed in, or TG001 saying how to install it.
-- Why: PostGIS is optional. tgsis's script never names a PostGIS object (it
-- must install, upgrade and restore without PostGIS), so the functions that
-- need PostGIS find it at run time, wherever CREATE EXTENSION put it, and
-- reach it only through this schema name, quoted (format %I).
CREATE FUNCTION tgsis.postgis_schema()
RETURNS name
LANGUAGE plpgsql
STABLE
PARALLEL SAFE
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_schema name;
BEGIN
    SELECT n.nspname INTO v_schema
      FROM pg_catalog.pg_extension e JOIN pg_catalog.pg_namespace n ON n.oid = e.extnamespace
     WHERE e.extname = 'postgis';
    IF NOT FOUND THEN
        RAISE EXCEPTION 'PostGIS is not installed in database %', current_database()
            USING ERRCODE = 'TG001',
                  DETAIL = 'The PostGIS functions of tgsis (TIN Z, POLYHEDRALSURFACE Z) need the postgis extension.',
                  HINT = 'a role with the right may run: CREATE EXTENSION postgis; then SELECT tgsis.enable_postgis();';
    END IF;
    RETURN v_schema;
END
$$;

COMMENT ON FUNCTION tgsis.postgis_schema() IS
    'the schema of the postgis extension in this database; raises TG001 when PostGIS is not installed';

-- ==== postgis/ewkb_geometry.sql ====
-- tgsis.ewkb_geometry(geoid, srid): a static geometry as PostGIS extended WKB (big-endian), built in SQL without PostGIS.
-- Why bytes and not PostGIS's geometry type: the extension script must
-- install and restore where PostGIS is absent, so no object of the script may
-- name a PostGIS type. EWKB is PostGIS's own exchange form: ST_GeomFromEWKB
-- (and the implicit cast bytea -> geometry) read it exactly, every coordinate
-- bit for bit (float8send is the IEEE 754 value, big-endian).
-- What each geotype becomes (docs/postgis.md):
--   SURFACE            TIN Z, one TRIANGLE Z per triangle, in trglid order
--   MULTITETRA         POLYHEDRALSURFACE Z of the solid's boundary: the faces
--                      that belong to one tetrahedron only, oriented outwards
--   MULTILINESTRING    MULTILINESTRING Z, one two-point LINESTRING per segment
--   MULTIPOINT         MULTIPOINT Z, one POINT Z per point
--   GEOMETRYCOLLECTION GEOMETRYCOLLECTION Z of its members, in order
-- z is elevation, as stored (a Depth file's z are negated on the way in).
-- p_srid NULL: no SRID in the header (members of a collection); 0: unknown.
-- Temporal surfaces have no shape without a time: tgsis.ewkb_geometry_at.
CREATE FUNCTION tgsis.ewkb_geometry(p_geoid bigint, p_srid integer DEFAULT NULL)
RETURNS bytea
LANGUAGE plpgsql
STABLE
PARALLEL SAFE
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    -- EWKB type words: the wkbZ flag 0x80000000, with wkbSRID 0x20000000 when an SRID follows
    v_z      constant integer := -2147483648;
    v_zsrid  constant integer := -1610612736;
    v_geo    record;
    v_code   integer;
    v_count  integer;
    v_body   bytea;
    v_member bigint;
BEGIN
    SELECT g.geotype, g.timemodel, g.geoids INTO v_geo FROM tgsis.geometry g WHERE g.geoid = p_geoid;
    IF NOT FOUND THEN
        RAISE EXCEPTION 'geometry % does not exist', coalesce(p_geoid::text, 'NULL')
            USING ERRCODE = 'TG200', HINT = 'SELECT _geoid FROM <class> lists the features of a class';
    END IF;
    IF v_geo.geotype NOT IN ('MULTIPOINT', 'MULTILINESTRING', 'SURFACE', 'MULTITETRA', 'GEOMETRYCOLLECTION') THEN
        RAISE EXCEPTION 'geometry % is a % (data model %), which has no PostGIS form', p_geoid, v_geo.geotype, v_geo.timemodel
            USING ERRCODE = 'TG100',
                  HINT = 'PostGIS forms exist for MULTIPOINT, MULTILINESTRING, SURFACE, MULTITETRA and GEOMETRYCOLLECTION';
    END IF;
    IF v_geo.timemodel <> 'STATIC' THEN
        RAISE EXCEPTION 'geometry % is a % surface: its shape depends on the time', p_geoid, v_geo.timemodel
            USING ERRCODE = 'TG100', HINT = 'take its shape at a time t: tgsis.postgis_geometry_at(class, geoid, t)';
    END IF;
    IF p_srid < 0 THEN
        RAISE EXCEPTION 'SRID % is not an id >= 0', p_srid USING ERRCODE = 'TG100';
    END IF;
    CASE v_geo.geotype
    WHEN 'SURFACE' THEN
        v_code := 16;  -- TIN
        SELECT count(*), string_agg('\x00'::bytea || int4send(v_z + 17) || int4send(1) || int4send(4)
                                    || a.p || b.p || c.p || a.p, ''::bytea ORDER BY t.trglid)
          INTO v_count, v_body
          FROM tgsis.trgl t
          CROSS JOIN LATERAL (SELECT float8send(v.x) || float8send(v.y) || float8send(v.z) AS p FROM tgsis.vrtx v
                               WHERE v.geoid = p_geoid AND v.vrtxid = t.vrtxid1) a
          CROSS JOIN LATERAL (SELECT float8send(v.x) || float8send(v.y) || float8send(v.z) AS p FROM tgsis.vrtx v
                               WHERE v.geoid = p_geoid AND v.vrtxid = t.vrtxid2) b
          CROSS JOIN LATERAL (SELECT float8send(v.x) || float8send(v.y) || float8send(v.z) AS p FROM tgsis.vrtx v
                               WHERE v.geoid = p_geoid AND v.vrtxid = t.vrtxid3) c
         WHERE t.geoid = p_geoid;
    WHEN 'MULTITETRA' THEN
        v_code := 15;  -- POLYHEDRALSURFACE
        WITH face AS (   -- the four faces of each tetrahedron, with the vertex opposite each
            SELECT t.tetraid, f.i, f.j, f.k, f.o
              FROM tgsis.tetra t
             CROSS JOIN LATERAL (VALUES (t.vrtxid1, t.vrtxid2, t.vrtxid3, t.vrtxid4), (t.vrtxid1, t.vrtxid2, t.vrtxid4, t.vrtxid3),
                                        (t.vrtxid1, t.vrtxid3, t.vrtxid4, t.vrtxid2), (t.vrtxid2, t.vrtxid3, t.vrtxid4, t.vrtxid1))
                   AS f(i, j, k, o)
             WHERE t.geoid = p_geoid
        ), border AS (   -- a face of one tetrahedron only is on the boundary (faces compared as sorted triples)
            SELECT f.*
              FROM (SELECT f.*, count(*) OVER (PARTITION BY least(f.i, f.j, f.k), greatest(f.i, f.j, f.k),
                                                            f.i + f.j + f.k - least(f.i, f.j, f.k) - greatest(f.i, f.j, f.k)) AS n
                      FROM face f) f
             WHERE f.n = 1
        ), placed AS (
            SELECT b.tetraid, b.i, b.j, b.k, pi.x AS xi, pi.y AS yi, pi.z AS zi, pj.x AS xj, pj.y AS yj, pj.z AS zj,
                   pk.x AS xk, pk.y AS yk, pk.z AS zk, po.x - pi.x AS dx, po.y - pi.y AS dy, po.z - pi.z AS dz
              FROM border b
              JOIN tgsis.vrtx pi ON pi.geoid = p_geoid AND pi.vrtxid = b.i
              JOIN tgsis.vrtx pj ON pj.geoid = p_geoid AND pj.vrtxid = b.j
              JOIN tgsis.vrtx pk ON pk.geoid = p_geoid AND pk.vrtxid = b.k
              JOIN tgsis.vrtx po ON po.geoid = p_geoid AND po.vrtxid = b.o
        ), oriented AS (   -- outwards: the normal (pj - pi) x (pk - pi) points away from the opposite vertex
            SELECT p.tetraid, p.i, p.j, p.k,
                   float8send(p.xi) || float8send(p.yi) || float8send(p.zi) AS a,
                   float8send(p.xj) || float8send(p.yj) || float8send(p.zj) AS b,
                   float8send(p.xk) || float8send(p.yk) || float8send(p.zk) AS c,
                   ((p.yj - p.yi) * (p.zk - p.zi) - (p.zj - p.zi) * (p.yk - p.yi)) * p.dx
                 + ((p.zj - p.zi) * (p.xk - p.xi) - (p.xj - p.xi) * (p.zk - p.zi)) * p.dy
                 + ((p.xj - p.xi) * (p.yk - p.yi) - (p.yj - p.yi) * (p.xk - p.xi)) * p.dz > 0 AS inwards
              FROM placed p
        )
        SELECT count(*), string_agg('\x00'::bytea || int4send(v_z + 3) || int4send(1) || int4send(4) || o.a
                                    || CASE WHEN o.inwards THEN o.c || o.b ELSE o.b || o.c END || o.a,
                                    ''::bytea ORDER BY o.tetraid, o.i, o.j, o.k)
          INTO v_count, v_body
          FROM oriented o;
    WHEN 'MULTILINESTRING' THEN
        v_code := 5;
        SELECT count(*), string_agg('\x00'::bytea || int4send(v_z + 2) || int4send(2)
                                    || float8send(a.x) || float8send(a.y) || float8send(a.z)
                                    || float8send(b.x) || float8send(b.y) || float8send(b.z), ''::bytea ORDER BY s.segid)
          INTO v_count, v_body
          FROM tgsis.segment s
          JOIN tgsis.vrtx a ON a.geoid = p_geoid AND a.vrtxid = s.vrtxid1
          JOIN tgsis.vrtx b ON b.geoid = p_geoid AND b.vrtxid = s.vrtxid2
         WHERE s.geoid = p_geoid;
    WHEN 'MULTIPOINT' THEN
        v_code := 4;
        SELECT count(*), string_agg('\x00'::bytea || int4send(v_z + 1)
                                    || float8send(a.x) || float8send(a.y) || float8send(a.z), ''::bytea ORDER BY p.pointid)
          INTO v_count, v_body
          FROM tgsis.point p
          JOIN tgsis.vrtx a ON a.geoid = p_geoid AND a.vrtxid = p.vrtxid1
         WHERE p.geoid = p_geoid;
    ELSE  -- GEOMETRYCOLLECTION (the only geotype left): its members without SRIDs of their own (the collection carries it)
        v_code := 7;
        v_count := 0;
        v_body := '';
        FOREACH v_member IN ARRAY v_geo.geoids LOOP
            v_body := v_body || tgsis.ewkb_geometry(v_member, NULL);
            v_count := v_count + 1;
        END LOOP;
    END CASE;
    RETURN '\x00'::bytea
           || CASE WHEN p_srid IS NULL THEN int4send(v_z + v_code) ELSE int4send(v_zsrid + v_code) || int4send(p_srid) END
           || int4send(v_count) || coalesce(v_body, '');
END
$$;

COMMENT ON FUNCTION tgsis.ewkb_geometry(bigint, integer) IS
    'a static geometry as PostGIS EWKB with SRID p_srid (NULL: none): SURFACE as TIN Z, MULTITETRA as the POLYHEDRALSURFACE Z of its boundary (outward faces), MULTILINESTRING Z of its segments, MULTIPOINT Z, GEOMETRYCOLLECTION Z of its members; built without PostGIS (ST_GeomFromEWKB reads it)';

-- ==== postgis/ewkb_geometry_at.sql ====
-- tgsis.ewkb_geometry_at(geoid, t, convention, srid): a geometry's shape at model time t as PostGIS EWKB, or NULL when it does not exist then.
-- Why: models 2 and 3 have a shape only at a time; this is tgsis.vertices_at
-- and tgsis.triangles_at (the same snapshot as Python's get_at, to the bit)
-- written as a TIN Z. NULL rather than an empty TIN outside the feature's
-- life, as get_at gives None. Static geometries: their one shape at every t.
-- Built without PostGIS (see tgsis.ewkb_geometry for why).
CREATE FUNCTION tgsis.ewkb_geometry_at(p_geoid bigint, p_t double precision, p_convention text DEFAULT 'left',
                                       p_srid integer DEFAULT NULL)
RETURNS bytea
LANGUAGE plpgsql
STABLE
PARALLEL SAFE
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_z     constant integer := -2147483648;
    v_zsrid constant integer := -1610612736;
    v_model text;
    v_count integer;
    v_body  bytea;
BEGIN
    PERFORM tgsis.checked_time(p_t), tgsis.checked_convention(p_convention);
    SELECT g.timemodel INTO v_model FROM tgsis.geometry g WHERE g.geoid = p_geoid;
    IF NOT FOUND THEN
        RAISE EXCEPTION 'geometry % does not exist', coalesce(p_geoid::text, 'NULL')
            USING ERRCODE = 'TG200', HINT = 'SELECT _geoid FROM <class> lists the features of a class';
    END IF;
    IF v_model NOT IN ('INSTANTS', 'EVOLVING') THEN   -- static (or no PostGIS form: ewkb_geometry says so)
        RETURN tgsis.ewkb_geometry(p_geoid, p_srid);
    END IF;
    IF p_srid < 0 THEN
        RAISE EXCEPTION 'SRID % is not an id >= 0', p_srid USING ERRCODE = 'TG100';
    END IF;
    IF NOT tgsis.exists_at(p_geoid, p_t, p_convention) THEN
        RETURN NULL;
    END IF;
    WITH v AS MATERIALIZED (
        SELECT v.vrtxid, float8send(v.x) || float8send(v.y) || float8send(v.z) AS p
          FROM tgsis.vertices_at(p_geoid, p_t, p_convention) v
    )
    SELECT count(*), string_agg('\x00'::bytea || int4send(v_z + 17) || int4send(1) || int4send(4)
                                || a.p || b.p || c.p || a.p, ''::bytea ORDER BY t.trglid)
      INTO v_count, v_body
      FROM tgsis.triangles_at(p_geoid, p_t, p_convention) t
      JOIN v a ON a.vrtxid = t.vrtxid1
      JOIN v b ON b.vrtxid = t.vrtxid2
      JOIN v c ON c.vrtxid = t.vrtxid3;
    RETURN '\x00'::bytea
           || CASE WHEN p_srid IS NULL THEN int4send(v_z + 16) ELSE int4send(v_zsrid + 16) || int4send(p_srid) END
           || int4send(v_count) || coalesce(v_body, '');
END
$$;

COMMENT ON FUNCTION tgsis.ewkb_geometry_at(bigint, double precision, text, integer) IS
    'a geometry''s shape at model time t as PostGIS EWKB (a temporal surface: TIN Z of tgsis.vertices_at and triangles_at; a static geometry: as tgsis.ewkb_geometry), NULL when it does not exist at t; built without PostGIS';

-- ==== postgis/feature_srid.sql ====
-- tgsis.feature_srid(class, geoid): the SRID of a feature of a class (the class's SRS), or TG200 naming what is missing.
-- Why: a geometry row does not know its class, and PostGIS geometries carry
-- their SRID, which is the class's srs (tgsis.catalog). Checking that the
-- feature is one of the class's also keeps a wrong pair (class, id) from
-- giving a geometry the SRID of another class. The feature table is read as
-- the caller, through its name (under feature versioning: the caller's version).
CREATE FUNCTION tgsis.feature_srid(p_class text, p_geoid bigint)
RETURNS integer
LANGUAGE plpgsql
STABLE
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_class tgsis.catalog := tgsis.catalog_row(p_class);
    v_found boolean;
BEGIN
    EXECUTE format('SELECT EXISTS (SELECT FROM %I.%I WHERE _geoid = $1)', v_class.schemaname, v_class.featuretable)
       INTO v_found USING p_geoid;
    IF NOT v_found THEN
        RAISE EXCEPTION 'feature % of class % does not exist', coalesce(p_geoid::text, 'NULL'), p_class
            USING ERRCODE = 'TG200', HINT = format('SELECT _geoid FROM %I.%I lists its features', v_class.schemaname,
                                                   v_class.featuretable);
    END IF;
    RETURN v_class.srs;
END
$$;

COMMENT ON FUNCTION tgsis.feature_srid(text, bigint) IS
    'the SRID (the class''s srs) of a feature of a class; raises TG200 when the class or the feature does not exist';

-- ==== postgis/mesh_from_postgis.sql ====
-- tgsis.mesh_from_postgis(geom): a PostGIS geometry as a tgsis mesh: geotype, vertices (n x 3) and cells (m x k, 0-based).
-- Why polymorphic (anyelement) and dynamic SQL: the script may not name
-- PostGIS's type (PostGIS is optional, see tgsis.ewkb_geometry), so the
-- argument is checked to be PostGIS's geometry at run time and PostGIS's
-- functions are reached through its schema, quoted. The inverse of
-- tgsis.postgis_geometry: TIN Z, POLYHEDRALSURFACE Z, (MULTI)POLYGON Z and
-- TRIANGLE Z give a SURFACE (a face of more than three corners is split into
-- a fan of triangles; a solid's boundary stays a surface: no tetrahedra are
-- made up), (MULTI)LINESTRING Z a MULTILINESTRING of its segments,
-- (MULTI)POINT Z a MULTIPOINT. Vertices that repeat the same coordinates
-- are one vertex (as the faces of a TIN share corners), numbered in order of
-- first appearance.
CREATE FUNCTION tgsis.mesh_from_postgis(p_geom anyelement)
RETURNS TABLE (geotype text, vertices double precision[], cells bigint[])
LANGUAGE plpgsql
STABLE
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_ps    name := tgsis.postgis_schema();
    v_type  text;
    v_dims  integer;
    v_holes boolean;
    v_kind  text;
BEGIN
    IF pg_typeof(p_geom) <> format('%I.geometry', v_ps)::regtype THEN
        RAISE EXCEPTION 'a % is not a PostGIS geometry', pg_typeof(p_geom)
            USING ERRCODE = 'TG100', HINT = format('give a geometry, e.g. %s.ST_GeomFromText(''TIN Z (...)'')', quote_ident(v_ps));
    END IF;
    IF p_geom IS NULL THEN
        RAISE EXCEPTION 'the geometry is NULL' USING ERRCODE = 'TG100';
    END IF;
    EXECUTE format('SELECT %1$I.st_geometrytype($1), %1$I.st_ndims($1), %1$I.st_isempty($1)', v_ps)
       INTO v_type, v_dims, v_holes USING p_geom;
    IF v_holes THEN
        RAISE EXCEPTION 'the geometry (%) is empty', v_type
            USING ERRCODE = 'TG102', HINT = 'a tgsis object has at least one vertex';
    END IF;
    IF v_dims <> 3 THEN
        RAISE EXCEPTION 'the geometry (%) has % coordinates per point, not x, y, z', v_type, v_dims
            USING ERRCODE = 'TG102',
                  HINT = CASE WHEN v_dims = 2 THEN 'ST_Force3DZ(geom) gives it z = 0' ELSE 'ST_Force3DZ(geom) drops the measure' END;
    END IF;
    v_kind := CASE WHEN v_type IN ('ST_Tin', 'ST_Triangle', 'ST_Polygon', 'ST_MultiPolygon', 'ST_PolyhedralSurface') THEN 'SURFACE'
                   WHEN v_type IN ('ST_LineString', 'ST_MultiLineString') THEN 'MULTILINESTRING'
                   WHEN v_type IN ('ST_Point', 'ST_MultiPoint') THEN 'MULTIPOINT' END;
    IF v_kind IS NULL THEN
        RAISE EXCEPTION 'a PostGIS % has no tgsis geotype', v_type
            USING ERRCODE = 'TG102',
                  HINT = 'give a TIN, POLYHEDRALSURFACE, (MULTI)POLYGON or TRIANGLE (a SURFACE), a (MULTI)LINESTRING or a (MULTI)POINT, with Z; ST_Dump splits a collection';
    END IF;
    IF v_kind = 'SURFACE' THEN
        -- every corner of every face's outer ring (the ring closes on its first corner)
        EXECUTE format($q$
            SELECT EXISTS (SELECT FROM %1$I.st_dumppoints($1) d WHERE d.path[array_length(d.path, 1) - 1] > 1)$q$, v_ps)
           INTO v_holes USING p_geom;
        IF v_holes THEN
            RAISE EXCEPTION 'a face of the % has holes (inner rings)', v_type
                USING ERRCODE = 'TG102', HINT = 'triangulate it first (ST_Tesselate with SFCGAL, or ST_TriangulatePolygon)';
        END IF;
    END IF;
    -- window functions only (no self-joins of the points, which the planner may nest): linear in the points
    RETURN QUERY EXECUTE format($q$
        WITH p AS (   -- the points in order; part = the face or line, pos = the point in it
            SELECT row_number() OVER () AS ord,
                   CASE WHEN array_length(d.path, 1) >= 2 AND $2 = 'SURFACE' THEN d.path[array_length(d.path, 1) - 2]
                        WHEN array_length(d.path, 1) >= 2 THEN d.path[array_length(d.path, 1) - 1]
                        ELSE 1 END AS part,
                   d.path[array_length(d.path, 1)] AS pos,
                   %1$I.st_x(d.geom) AS x, %1$I.st_y(d.geom) AS y, %1$I.st_z(d.geom) AS z
              FROM %1$I.st_dumppoints($1) d
        ), f AS (     -- the first appearance of each position
            SELECT p.*, min(p.ord) OVER (PARTITION BY p.x, p.y, p.z) AS firstord FROM p
        ), v AS (     -- one vertex per distinct position, numbered by first appearance
            SELECT f.*, dense_rank() OVER (ORDER BY f.firstord) - 1 AS vid,
                   count(*) OVER (PARTITION BY f.part) AS n
              FROM f
        ), w AS (
            SELECT v.ord, v.pos, v.n, v.vid, v.x, v.y, v.z, v.firstord,
                   first_value(v.vid) OVER (PARTITION BY v.part ORDER BY v.pos) AS first,
                   lead(v.vid) OVER (PARTITION BY v.part ORDER BY v.pos) AS next
              FROM v
        )
        SELECT $2,
               (SELECT array_agg(ARRAY[w.x, w.y, w.z] ORDER BY w.vid) FROM w WHERE w.ord = w.firstord),
               (SELECT array_agg(CASE $2 WHEN 'SURFACE' THEN ARRAY[w.first, w.vid, w.next]     -- faces: fans from the first corner
                                         WHEN 'MULTILINESTRING' THEN ARRAY[w.vid, w.next]      -- lines: consecutive points
                                         ELSE ARRAY[w.vid] END ORDER BY w.ord)
                  FROM w
                 WHERE CASE $2 WHEN 'SURFACE' THEN w.pos BETWEEN 2 AND w.n - 2
                               WHEN 'MULTILINESTRING' THEN w.next IS NOT NULL
                               ELSE true END)
        $q$, v_ps)
        USING p_geom, v_kind;
END
$$;

COMMENT ON FUNCTION tgsis.mesh_from_postgis(anyelement) IS
    'a PostGIS geometry with Z as a tgsis mesh (geotype; vertices n x 3; cells m x k of 0-based vertex positions): TIN, POLYHEDRALSURFACE, (MULTI)POLYGON, TRIANGLE give a SURFACE (faces fanned into triangles), (MULTI)LINESTRING a MULTILINESTRING of segments, (MULTI)POINT a MULTIPOINT; equal positions are one vertex';

-- ==== postgis/insert_postgis_feature.sql ====
-- tgsis.insert_postgis_feature(class, geom, properties, name): store a PostGIS geometry as a new feature of a static class; returns its id.
-- Why in SQL: a psql or QGIS user holding PostGIS geometries (an imported
-- TIN, a digitised fault trace) stores them without a client. The geometry
-- is read by tgsis.mesh_from_postgis; the rows go in with plain INSERTs
-- through the names a psql user writes (under feature versioning: the
-- versioned views, in the session's version), then tgsis.refresh_geometry
-- sets the box and counts, in the caller's transaction: an error leaves
-- nothing behind. It runs as the caller (an editor writes features). Only
-- static classes without vertex or cell properties: the geometry carries
-- none, and a temporal class needs its instants (use Python's insert_feature).
CREATE FUNCTION tgsis.insert_postgis_feature(p_class text, p_geom anyelement, p_properties jsonb DEFAULT '{}',
                                             p_name text DEFAULT NULL)
RETURNS bigint
LANGUAGE plpgsql
VOLATILE
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_class tgsis.catalog := tgsis.catalog_row(p_class);
    v_mesh  record;
    v_geoid bigint;
    v_extra text[];
    v_bad   bigint;
BEGIN
    IF v_class.timemodel <> 'STATIC' THEN
        RAISE EXCEPTION 'feature class % is %: its features have instants, which a PostGIS geometry does not give', p_class,
                v_class.timemodel
            USING ERRCODE = 'TG100', HINT = 'store temporal features from Python (tgsis.insert_feature) or a static class';
    END IF;
    IF jsonb_array_length(v_class.cell_properties) > 0 THEN
        RAISE EXCEPTION 'feature class % has vertex or cell properties, which a PostGIS geometry does not carry', p_class
            USING ERRCODE = 'TG103', HINT = 'store the feature from Python (tgsis.insert_feature) with its properties';
    END IF;
    IF p_properties IS NULL OR jsonb_typeof(p_properties) <> 'object' THEN
        RAISE EXCEPTION 'the feature properties must be a JSON object, not %', coalesce(jsonb_typeof(p_properties), 'NULL')
            USING ERRCODE = 'TG100', HINT = 'e.g. ''{"name": "F1"}''';
    END IF;
    SELECT array_agg(k ORDER BY k) INTO v_extra
      FROM jsonb_object_keys(p_properties) k
     WHERE NOT EXISTS (SELECT FROM jsonb_array_elements(v_class.feature_properties) f WHERE f->>'name' = k);
    IF v_extra IS NOT NULL THEN
        RAISE EXCEPTION 'feature class % has no feature properties %', p_class, array_to_string(v_extra, ', ')
            USING ERRCODE = 'TG103',
                  HINT = format('its properties: %s',
                                coalesce((SELECT string_agg(f->>'name', ', ') FROM jsonb_array_elements(v_class.feature_properties) f),
                                         'none'));
    END IF;
    SELECT * INTO v_mesh FROM tgsis.mesh_from_postgis(p_geom);
    IF v_mesh.geotype <> v_class.geotype THEN
        RAISE EXCEPTION 'feature class % holds % features; the geometry is a %', p_class, v_class.geotype, v_mesh.geotype
            USING ERRCODE = 'TG100',
                  HINT = 'SURFACE: TIN, POLYHEDRALSURFACE, (MULTI)POLYGON; MULTILINESTRING: (MULTI)LINESTRING; MULTIPOINT: (MULTI)POINT';
    END IF;
    SELECT c INTO v_bad FROM generate_subscripts(v_mesh.cells, 1) c
     WHERE (SELECT count(DISTINCT v) FROM unnest(v_mesh.cells[c:c]) v) < array_length(v_mesh.cells, 2)
     LIMIT 1;
    IF v_bad IS NOT NULL THEN
        RAISE EXCEPTION 'cell % of the geometry repeats a vertex (a degenerate face or a zero-length segment)', v_bad - 1
            USING ERRCODE = 'TG102', HINT = 'ST_RemoveRepeatedPoints(geom) removes repeated points';
    END IF;

    v_geoid := tgsis.new_geometry(v_class.geotype, p_name, NULL, 0, 0);
    INSERT INTO tgsis.vrtx (geoid, vrtxid, x, y, z)
    SELECT v_geoid, i - 1, v_mesh.vertices[i][1], v_mesh.vertices[i][2], v_mesh.vertices[i][3]
      FROM generate_subscripts(v_mesh.vertices, 1) i;
    CASE v_class.geotype
    WHEN 'SURFACE' THEN
        INSERT INTO tgsis.trgl (geoid, trglid, vrtxid1, vrtxid2, vrtxid3)
        SELECT v_geoid, i - 1, v_mesh.cells[i][1], v_mesh.cells[i][2], v_mesh.cells[i][3]
          FROM generate_subscripts(v_mesh.cells, 1) i;
    WHEN 'MULTILINESTRING' THEN
        INSERT INTO tgsis.segment (geoid, segid, vrtxid1, vrtxid2)
        SELECT v_geoid, i - 1, v_mesh.cells[i][1], v_mesh.cells[i][2] FROM generate_subscripts(v_mesh.cells, 1) i;
    ELSE
        INSERT INTO tgsis.point (geoid, pointid, vrtxid1)
        SELECT v_geoid, i - 1, v_mesh.cells[i][1] FROM generate_subscripts(v_mesh.cells, 1) i;
    END CASE;
    PERFORM tgsis.refresh_geometry(v_geoid);
    EXECUTE format('INSERT INTO %I.%I SELECT * FROM jsonb_populate_record(NULL::%I.%I, $1)',
                   v_class.schemaname, v_class.featuretable, v_class.schemaname, v_class.featuretable)
      USING p_properties || jsonb_build_object('_geoid', v_geoid);
    RETURN v_geoid;
END
$$;

COMMENT ON FUNCTION tgsis.insert_postgis_feature(text, anyelement, jsonb, text) IS
    'store a PostGIS geometry with Z (TIN, POLYHEDRALSURFACE, polygons, lines, points: see tgsis.mesh_from_postgis) as a new feature of a static class without vertex or cell properties, with the given feature properties and name; returns its id';

-- ==== postgis/enable_postgis.sql ====
-- tgsis.enable_postgis(): create the functions that return PostGIS geometries, once PostGIS is installed; returns PostGIS's schema.
-- Why created at run time and not by the extension script: their return type
-- is PostGIS's geometry, which exists only where PostGIS is installed, and
-- tgsis must install, upgrade and restore without it, and with PostGIS
-- installed before or after tgsis. Everything with substance is in the
-- script and needs no PostGIS (tgsis.ewkb_geometry, ewkb_geometry_at,
-- feature_srid); the functions made here are one-line wrappers around it
-- that name PostGIS's type and ST_GeomFromEWKB in PostGIS's schema (quoted).
-- Created after CREATE EXTENSION, they are no extension members on either
-- install route: pg_dump dumps them whole, after CREATE EXTENSION postgis
-- (they depend on its type), like the storage tables (docs/install.md,
-- "Backup and restore"; docs/postgis.md). Never call this from an extension
-- script (the wrappers would become members and vanish from dumps);
-- tgsis.install calls it again after an upgrade when they exist.
-- It runs as tgsis's owner, who owns schema tgsis, for members of tgsis_admin.
CREATE FUNCTION tgsis.enable_postgis()
RETURNS name
LANGUAGE plpgsql
VOLATILE
SECURITY DEFINER
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_ps name;
BEGIN
    IF NOT pg_has_role(tgsis.calling_role(), 'tgsis_admin', 'MEMBER') THEN
        RAISE EXCEPTION 'role % may not enable the PostGIS functions of tgsis', tgsis.calling_role()
            USING ERRCODE = 'TG002', DETAIL = 'Creating functions in schema tgsis is for members of tgsis_admin.',
                  HINT = format('a DBA may run: GRANT tgsis_admin TO %I; or ask one to run SELECT tgsis.enable_postgis()',
                                tgsis.calling_role());
    END IF;
    v_ps := tgsis.postgis_schema();
    EXECUTE format($f$
        CREATE OR REPLACE FUNCTION tgsis.postgis_geometry(p_class text, p_geoid bigint)
        RETURNS %1$I.geometry
        LANGUAGE sql
        STABLE
        PARALLEL SAFE
        AS $body$ SELECT %1$I.st_geomfromewkb(tgsis.ewkb_geometry(p_geoid, tgsis.feature_srid(p_class, p_geoid))) $body$
        $f$, v_ps);
    EXECUTE format($f$
        CREATE OR REPLACE FUNCTION tgsis.postgis_geometry_at(p_class text, p_geoid bigint, p_t double precision,
                                                             p_convention text DEFAULT 'left')
        RETURNS %1$I.geometry
        LANGUAGE sql
        STABLE
        PARALLEL SAFE
        AS $body$
            SELECT %1$I.st_geomfromewkb(tgsis.ewkb_geometry_at(p_geoid, p_t, p_convention, tgsis.feature_srid(p_class, p_geoid)))
        $body$
        $f$, v_ps);
    COMMENT ON FUNCTION tgsis.postgis_geometry(text, bigint) IS
        'a feature of a static class as a PostGIS geometry with the class''s SRS as SRID: SURFACE as TIN Z, MULTITETRA as the POLYHEDRALSURFACE Z of its boundary, MULTILINESTRING Z, MULTIPOINT Z, GEOMETRYCOLLECTION Z (created by tgsis.enable_postgis)';
    COMMENT ON FUNCTION tgsis.postgis_geometry_at(text, bigint, double precision, text) IS
        'a feature''s shape at model time t as a PostGIS geometry (a temporal surface: TIN Z of its snapshot), NULL when it does not exist at t (created by tgsis.enable_postgis)';
    RETURN v_ps;
END
$$;

REVOKE ALL ON FUNCTION tgsis.enable_postgis() FROM PUBLIC;
GRANT EXECUTE ON FUNCTION tgsis.enable_postgis() TO tgsis_admin;

COMMENT ON FUNCTION tgsis.enable_postgis() IS
    'create tgsis.postgis_geometry(class, geoid) and tgsis.postgis_geometry_at(class, geoid, t, convention), which return PostGIS geometries, once PostGIS is installed (TG001 otherwise); returns PostGIS''s schema. For tgsis_admin; run it again after PostGIS moves';

-- ==== postgis/postgis_rows.sql ====
-- tgsis.postgis_rows(class): the rows of a class's PostGIS view: each feature's columns, the instant (temporal classes) and its EWKB.
-- Why a function that reads the feature table through its name (dynamic SQL)
-- instead of a view that selects from it: a view on the feature table would
-- bind to that table, and feature versioning renames it to <class>_ver and
-- puts a view in its place (a plain view on it is refused, TG202). Read by
-- name, the rows are those of the caller's version, versioned or not.
-- Static classes: one row per feature; temporal classes: one per feature and
-- instant (tgsis.geometry_instants), its shape at that instant (left-closed:
-- the shape that holds from it on). Runs as the caller (readers may read).
CREATE FUNCTION tgsis.postgis_rows(p_class text)
RETURNS SETOF record
LANGUAGE plpgsql
STABLE
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_class tgsis.catalog := tgsis.catalog_row(p_class);
BEGIN
    IF v_class.timemodel = 'STATIC' THEN
        RETURN QUERY EXECUTE format('SELECT f.*, NULL::double precision, tgsis.ewkb_geometry(f._geoid, $1) FROM %I.%I f',
                                    v_class.schemaname, v_class.featuretable)
          USING v_class.srs;
    ELSE
        RETURN QUERY EXECUTE format('SELECT f.*, i.t, tgsis.ewkb_geometry_at(f._geoid, i.t, ''left'', $1)
                                       FROM %I.%I f CROSS JOIN LATERAL tgsis.geometry_instants(f._geoid) i',
                                    v_class.schemaname, v_class.featuretable)
          USING v_class.srs;
    END IF;
END
$$;

COMMENT ON FUNCTION tgsis.postgis_rows(text) IS
    'rows of a class''s PostGIS view (tgsis.create_postgis_view): the feature table''s columns, the instant (NULL for static classes) and the EWKB of the shape; reads the feature table by name, so that feature versioning can replace it';

-- ==== postgis/create_postgis_view.sql ====
-- tgsis.create_postgis_view(class): (re)create the view <class>_postgis: the class's features with a PostGIS geometry column geom.
-- Why: QGIS (and its 3D view) and PostGIS's own functions find layers as
-- relations with a geometry column whose type and SRID are declared (the
-- column's typmod, which geometry_columns reports): geom is
-- geometry(TINZ | POLYHEDRALSURFACEZ | MULTILINESTRINGZ | MULTIPOINTZ |
-- GEOMETRYCOLLECTIONZ, <class srs>). Created on request only, as it needs
-- PostGIS; it is no extension member and pg_dump dumps it (docs/postgis.md).
-- The view reads through tgsis.postgis_rows (which says why), with the
-- feature table's columns as they are now; temporal classes get one row per
-- feature and instant (_t). Readers may select it; it runs the functions as
-- the reader, so each sees their own version. It runs as tgsis's owner, who
-- owns the class's schema or is trusted there (register_feature_class), for
-- members of tgsis_admin; tgsis.drop_feature_class drops the view too.
CREATE FUNCTION tgsis.create_postgis_view(p_class text)
RETURNS regclass
LANGUAGE plpgsql
VOLATILE
SECURITY DEFINER
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_class   tgsis.catalog;
    v_ps      name;
    v_view    text;
    v_type    text;
    v_cols    text;
    v_defs    text;
    v_rel     regclass;
    v_column  record;
BEGIN
    IF NOT pg_has_role(tgsis.calling_role(), 'tgsis_admin', 'MEMBER') THEN
        RAISE EXCEPTION 'role % may not create PostGIS views of feature classes', tgsis.calling_role()
            USING ERRCODE = 'TG002', DETAIL = 'Creating views of feature classes is for members of tgsis_admin.',
                  HINT = format('a DBA may run: GRANT tgsis_admin TO %I', tgsis.calling_role());
    END IF;
    v_class := tgsis.catalog_row(p_class);
    IF v_class.geotype NOT IN ('MULTIPOINT', 'MULTILINESTRING', 'SURFACE', 'MULTITETRA', 'GEOMETRYCOLLECTION') THEN
        RAISE EXCEPTION 'feature class % holds % features, which have no PostGIS form', p_class, v_class.geotype
            USING ERRCODE = 'TG100',
                  HINT = 'PostGIS views exist for classes of MULTIPOINT, MULTILINESTRING, SURFACE, MULTITETRA and GEOMETRYCOLLECTION';
    END IF;
    v_ps := tgsis.postgis_schema();
    v_view := v_class.classname || '_postgis';
    v_type := CASE v_class.geotype WHEN 'SURFACE' THEN 'TINZ' WHEN 'MULTITETRA' THEN 'POLYHEDRALSURFACEZ'
                                   ELSE v_class.geotype || 'Z' END;
    v_rel := to_regclass(format('%I.%I', v_class.schemaname, v_view));
    -- only a view tgsis made (its owner, its comment) is replaced
    IF v_rel IS NOT NULL AND NOT (coalesce(obj_description(v_rel, 'pg_class'), '') LIKE 'tgsis PostGIS view %'
                                  AND (SELECT c.relkind = 'v' AND c.relowner = (SELECT relowner FROM pg_catalog.pg_class
                                                                               WHERE oid = 'tgsis.catalog'::regclass)
                                         FROM pg_catalog.pg_class c WHERE c.oid = v_rel)) THEN
        RAISE EXCEPTION 'relation %.% exists and is not the PostGIS view of class %', v_class.schemaname, v_view, p_class
            USING ERRCODE = 'TG201', HINT = format('rename or drop %I.%I, then call tgsis.create_postgis_view(%L) again',
                                                   v_class.schemaname, v_view, p_class);
    END IF;
    SELECT string_agg(format('r.%I', a.attname), ', ' ORDER BY a.attnum),
           string_agg(format('%I %s', a.attname, format_type(a.atttypid, a.atttypmod)), ', ' ORDER BY a.attnum)
      INTO v_cols, v_defs
      FROM pg_catalog.pg_attribute a
     WHERE a.attrelid = format('%I.%I', v_class.schemaname, v_class.featuretable)::regclass
       AND a.attnum > 0 AND NOT a.attisdropped;
    IF v_rel IS NOT NULL THEN   -- the columns may have changed: CREATE OR REPLACE VIEW cannot drop any
        EXECUTE format('DROP VIEW %s', v_rel);
    END IF;
    EXECUTE format('CREATE VIEW %I.%I AS SELECT %s, %s%I.st_geomfromewkb(r._ewkb)::%I.geometry(%s, %s) AS geom
                      FROM tgsis.postgis_rows(%L) AS r(%s, _t double precision, _ewkb bytea)',
                   v_class.schemaname, v_view, v_cols, CASE WHEN v_class.timemodel = 'STATIC' THEN '' ELSE 'r._t, ' END,
                   v_ps, v_ps, v_type, v_class.srs, v_class.classname, v_defs);
    v_rel := format('%I.%I', v_class.schemaname, v_view)::regclass;
    EXECUTE format('COMMENT ON VIEW %s IS %L', v_rel,
                   format('tgsis PostGIS view of feature class %s: its features with geom, a geometry(%s, %s)%s (tgsis.create_postgis_view)',
                          p_class, v_type, v_class.srs,
                          CASE WHEN v_class.timemodel = 'STATIC' THEN '' ELSE ', one row per feature and instant _t' END));
    FOR v_column IN
        SELECT a.attname, col_description(a.attrelid, a.attnum) AS note
          FROM pg_catalog.pg_attribute a
         WHERE a.attrelid = format('%I.%I', v_class.schemaname, v_class.featuretable)::regclass AND a.attnum > 0
           AND NOT a.attisdropped AND col_description(a.attrelid, a.attnum) IS NOT NULL
    LOOP
        EXECUTE format('COMMENT ON COLUMN %s.%I IS %L', v_rel, v_column.attname, v_column.note);
    END LOOP;
    EXECUTE format('COMMENT ON COLUMN %s.geom IS %L', v_rel,
                   format('the feature''s geometry (%s, SRID %s = the class''s srs; z up positive)%s', v_type, v_class.srs,
                          CASE WHEN v_class.timemodel = 'STATIC' THEN '' ELSE ' at instant _t' END));
    IF v_class.timemodel <> 'STATIC' THEN
        EXECUTE format('COMMENT ON COLUMN %s._t IS %L', v_rel,
                       'an instant of the feature (model time): the shape that holds from it on (left-closed)');
    END IF;
    EXECUTE format('GRANT SELECT ON %s TO tgsis_reader', v_rel);
    RETURN v_rel;
END
$$;

REVOKE ALL ON FUNCTION tgsis.create_postgis_view(text) FROM PUBLIC;
GRANT EXECUTE ON FUNCTION tgsis.create_postgis_view(text) TO tgsis_admin;

COMMENT ON FUNCTION tgsis.create_postgis_view(text) IS
    '(re)create <class>_postgis: the class''s features with geom, a PostGIS geometry(TINZ | POLYHEDRALSURFACEZ | ..., srs) column (temporal classes: one row per feature and instant _t), for QGIS and PostGIS queries; needs PostGIS (TG001), for tgsis_admin';

-- ==== checkin/table_fingerprint.sql ====
-- tgsis.table_fingerprint(schema, table, keyfield, idfield, keys): row count and xor of row hashes of some objects' rows.
-- Each row hashes as the xor of its columns' 64-bit extended hashes, each
-- seeded by the row's id and the column's position: equal rows hash equal,
-- swapping values between rows or columns changes the hash, and no row text
-- is built (twice as fast as hash_record_extended, which also needs a hash
-- function for every column type). A NULL hashes as a constant of its column.
-- The key and id columns are not hashed themselves: the key is the same on
-- every row counted (a row leaving the object changes the count) and a
-- changed id changes the seeds of the row's other columns.
-- Read through the table's name: through the versioned view when versioning is on.
CREATE FUNCTION tgsis.table_fingerprint(p_schema text, p_table text, p_keyfield text, p_idfield text, p_keys bigint[])
RETURNS text
LANGUAGE plpgsql
STABLE
AS $$
DECLARE
    v_hash   text;
    v_result text;
BEGIN
    IF to_regclass(format('%I.%I', p_schema, p_table)) IS NULL THEN
        RAISE EXCEPTION 'table %.% does not exist', quote_ident(p_schema), quote_ident(p_table) USING ERRCODE = 'TG200';
    END IF;
    SELECT string_agg(format(
               'coalesce(%s, %s)',
               CASE t.typname
                   WHEN 'int8' THEN format('hashint8extended(r.%I, r.%I * 64 + %s)', a.attname, p_idfield, a.attnum)
                   WHEN 'int4' THEN format('hashint4extended(r.%I, r.%I * 64 + %s)', a.attname, p_idfield, a.attnum)
                   WHEN 'int2' THEN format('hashint4extended(r.%I, r.%I * 64 + %s)', a.attname, p_idfield, a.attnum)
                   WHEN 'bool' THEN format('hashint4extended(r.%I::int, r.%I * 64 + %s)', a.attname, p_idfield, a.attnum)
                   WHEN 'float8' THEN format('hashfloat8extended(r.%I, r.%I * 64 + %s)', a.attname, p_idfield, a.attnum)
                   WHEN 'float4' THEN format('hashfloat8extended(r.%I, r.%I * 64 + %s)', a.attname, p_idfield, a.attnum)
                   WHEN 'numeric' THEN format('hash_numeric_extended(r.%I, r.%I * 64 + %s)', a.attname, p_idfield, a.attnum)
                   ELSE format('hashtextextended(r.%I::text, r.%I * 64 + %s)', a.attname, p_idfield, a.attnum)
               END,
               a.attnum), ' # ' ORDER BY a.attnum)
      INTO v_hash
      FROM pg_attribute a JOIN pg_type t ON t.oid = a.atttypid
     WHERE a.attrelid = format('%I.%I', p_schema, p_table)::regclass AND a.attnum > 0 AND NOT a.attisdropped
       AND a.attname NOT IN (p_keyfield, p_idfield);
    -- the key is the same on every row counted, and the id seeds every other column's hash
    v_hash := coalesce(v_hash, format('hashint8extended(r.%I, 0)', p_idfield));
    -- a versioned table is read from its storage with the view's predicate and the session's
    -- revision set as a parameter: the view's own calls to tgsis.get_revisions() would keep
    -- the scan from running in parallel (measured: twice as slow)
    IF EXISTS (SELECT FROM tgsis.versioned_tables t WHERE t.schemaname = p_schema AND t.tablename = p_table) THEN
        EXECUTE format('SELECT count(*) || '':'' || coalesce(bit_xor(%s), 0) FROM %I.%I r
                         WHERE r.%I = ANY ($1) AND (r.revision = ANY ($2)) IS TRUE
                           AND (NOT r.revclosed OR NOT (r.lastrevs && $2))',
                       v_hash, p_schema, p_table || '_ver', p_keyfield)
           INTO v_result USING p_keys, tgsis.get_revisions();
    ELSE
        EXECUTE format('SELECT count(*) || '':'' || coalesce(bit_xor(%s), 0) FROM %I.%I r WHERE r.%I = ANY ($1)',
                       v_hash, p_schema, p_table, p_keyfield)
           INTO v_result USING p_keys;
    END IF;
    RETURN v_result;
END
$$;

COMMENT ON FUNCTION tgsis.table_fingerprint(text, text, text, text, bigint[]) IS
    'row count and xor of per-row hashes (columns hashed with seeds from the row id and column position) of the rows of a table whose keyfield is one of keys, as the session sees them';

-- ==== checkin/object_fingerprint.sql ====
-- tgsis.object_fingerprint(geoid): a digest of everything the session's version holds of a model-1 feature.
-- Per table (the geometry row, its vertices, simplices, cell properties and
-- feature row; a collection's members too) the row count and the xor of the
-- 64-bit hashes of the rows (tgsis.table_fingerprint; bit_xor is safe: a
-- primary key never lets two equal rows cancel out), so that any insert, delete or change of
-- a value shows, whatever the row order. Read through the tables' names,
-- i.e. through the versioned views when versioning is on: it is the state
-- the session sees. Check-out keeps it; check-in compares it (no lost update).
CREATE FUNCTION tgsis.object_fingerprint(p_geoid bigint)
RETURNS text
LANGUAGE plpgsql
STABLE
AS $$
DECLARE
    v_geo     record;
    v_ids     bigint[];
    v_class   record;
    v_parts   text[] := '{}';
    v_part    text;
    v_table   text;
BEGIN
    SELECT geotype, timemodel INTO v_geo FROM tgsis.geometry WHERE geoid = p_geoid;
    IF NOT FOUND THEN
        RETURN NULL;
    END IF;
    IF v_geo.timemodel <> 'STATIC' THEN
        RAISE EXCEPTION 'geometry % is temporal (%): fingerprints are of static (model-1) objects', p_geoid, v_geo.timemodel
            USING ERRCODE = 'TG100';
    END IF;
    SELECT p_geoid || coalesce(array_agg(geoid ORDER BY geoid), '{}') INTO v_ids FROM tgsis.geometry WHERE collection = p_geoid;
    -- rows of the geometry and feature tables hash as text: cube (bbox) and some
    -- feature property types have no hash function, and there are few such rows
    SELECT count(*) || ':' || coalesce(bit_xor(hashtextextended(g::text, 0)), 0) INTO v_part
      FROM tgsis.geometry g WHERE g.geoid = ANY (v_ids);
    v_parts := v_parts || ('geometry ' || v_part);
    v_parts := v_parts || ('vrtx ' || tgsis.table_fingerprint('tgsis', 'vrtx', 'geoid', 'vrtxid', v_ids));
    v_parts := v_parts || ('atom ' || tgsis.table_fingerprint('tgsis', 'atom', 'geoid', 'vrtxid', v_ids));
    v_parts := v_parts || ('part ' || tgsis.table_fingerprint('tgsis', 'part', 'geoid', 'firstid', v_ids));
    FOR v_table IN SELECT DISTINCT tgsis.simplex_table(geotype) FROM tgsis.geometry
                    WHERE geoid = ANY (v_ids) AND geotype <> 'GEOMETRYCOLLECTION' ORDER BY 1 LOOP
        v_parts := v_parts || (v_table || ' ' || tgsis.table_fingerprint(
            'tgsis', v_table, 'geoid', CASE v_table WHEN 'point' THEN 'pointid' WHEN 'segment' THEN 'segid'
                                                     WHEN 'trgl' THEN 'trglid' ELSE 'tetraid' END, v_ids));
    END LOOP;
    FOR v_class IN SELECT schemaname, featuretable, cellprotable, otherprotable FROM tgsis.catalog
                    WHERE geotype = v_geo.geotype AND timemodel = 'STATIC' ORDER BY classname LOOP
        EXECUTE format('SELECT count(*) || '':'' || coalesce(bit_xor(hashtextextended(f::text, 0)), 0) FROM %I.%I f WHERE f._geoid = $1',
                       v_class.schemaname, v_class.featuretable)
           INTO v_part USING p_geoid;
        v_parts := v_parts || (v_class.featuretable || ' ' || v_part);
        v_parts := v_parts || (v_class.cellprotable || ' ' || tgsis.table_fingerprint(
            v_class.schemaname, v_class.cellprotable, '_geoid', '_idx', v_ids));
        IF v_class.otherprotable IS NOT NULL THEN
            v_parts := v_parts || (v_class.otherprotable || ' ' || tgsis.table_fingerprint(
                v_class.schemaname, v_class.otherprotable, '_geoid', '_idx', v_ids));
        END IF;
    END LOOP;
    RETURN md5(array_to_string(v_parts, '|'));
END
$$;

COMMENT ON FUNCTION tgsis.object_fingerprint(bigint) IS
    'digest (md5 of per-table row counts and xor of row hashes) of a static feature''s rows as the session''s version sees them: geometry, vertices, simplices, atoms, parts, cell properties, feature row, members; NULL when the geometry does not exist';

-- ==== checkin/check_unchanged.sql ====
-- tgsis.check_unchanged(geoid, fingerprint, revision): TG304 unless the object is as it was checked out.
-- Takes tgsis.feature_write_lock first, so that of two check-ins of the same
-- object from the same base the second waits for the first and then sees
-- its change. p_revision (the working revision at check-out) only serves
-- the message.
CREATE FUNCTION tgsis.check_unchanged(p_geoid bigint, p_fingerprint text, p_revision integer DEFAULT NULL)
RETURNS void
LANGUAGE plpgsql
VOLATILE
AS $$
DECLARE
    v_now      text;
    v_version  text := tgsis.get_working_version();
BEGIN
    IF p_geoid IS NULL OR p_fingerprint IS NULL THEN
        RAISE EXCEPTION 'check_unchanged needs a geoid and the fingerprint taken at check-out, got % and %',
                        coalesce(p_geoid::text, 'NULL'), coalesce(quote_literal(p_fingerprint), 'NULL')
            USING ERRCODE = 'TG100', HINT = 'SELECT tgsis.object_fingerprint(geoid) at check-out gives the fingerprint';
    END IF;
    PERFORM tgsis.require_read_committed('a check-in');
    PERFORM tgsis.feature_write_lock(p_geoid);
    v_now := tgsis.object_fingerprint(p_geoid);
    IF v_now IS NULL THEN
        RAISE EXCEPTION 'feature % was deleted from version % since it was checked out%', p_geoid, quote_literal(v_version),
                        coalesce(format(' (at revision %s)', p_revision), '')
            USING ERRCODE = 'TG304',
                  HINT = 'insert the edited mesh as a new feature, or check out another feature';
    END IF;
    IF v_now IS DISTINCT FROM p_fingerprint THEN
        RAISE EXCEPTION 'feature % was changed in version % since it was checked out%', p_geoid, quote_literal(v_version),
                        coalesce(format(' (at revision %s)', p_revision), '')
            USING ERRCODE = 'TG304',
                  DETAIL = 'Another writer changed the object meanwhile; checking in would overwrite that change.',
                  HINT = 'check in into a new child version (on_conflict="child", tgsis checkin --on-conflict child) and merge, or check out again and redo the edit';
    END IF;
END
$$;

COMMENT ON FUNCTION tgsis.check_unchanged(bigint, text, integer) IS
    'lock a feature for writing (tgsis.feature_write_lock) and raise TG304 unless its fingerprint is still the one taken at check-out';

-- ==== checkin/checkout_revision.sql ====
-- tgsis.checkout_revision(): the frozen revision whose state a check-out reads, freezing the working revision if need be; NULL when nothing can be frozen.
-- Why: a version's working revision stays open for writes, and a write in it
-- is made in place, so the state a check-out saw in it could not be found
-- again once a colleague changed the object. Frozen, it stays stored: a
-- conflicting check-in can base its child version on it (create_version's
-- p_base), so that the two edits meet as a conflict of the normal merge path.
-- In the session's version:
--   viewing an older revision: that revision (frozen already; nothing written);
--   feature versioning off, a read-only transaction, or a role without the
--   write right: NULL, without writing or locking anything (readers check out
--   as before; their check-in cannot take the child path);
--   a REPEATABLE READ or SERIALIZABLE transaction: NULL too, because its
--   snapshot may predate writes the freeze waited for, so what it reads is
--   not what the frozen revision holds;
--   otherwise the working revision is frozen (tgsis.next_working_revision
--   under the version's row lock, which waits for open writers of the version,
--   as create_version and save_revision do) and returned.
-- Costs: one revision per check-out in the version's working set (and in the
-- sets of children created later); compress_versions removes it when no
-- version, name or child needs it, after which such a check-in's child path
-- is refused (TG200 from create_version).
CREATE FUNCTION tgsis.checkout_revision()
RETURNS integer
LANGUAGE plpgsql
VOLATILE
SECURITY DEFINER
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_name    text := tgsis.get_working_version();
    v_viewing integer := tgsis.get_viewing_revision();
    v_version tgsis.versions;
BEGIN
    SELECT * INTO v_version FROM tgsis.versions WHERE name = v_name;
    IF NOT FOUND THEN
        RAISE EXCEPTION 'version % does not exist', quote_literal(v_name)
            USING ERRCODE = 'TG200', HINT = 'SELECT tgsis.goto_version(''DEFAULT'')';
    END IF;
    IF v_viewing IS NOT NULL AND v_viewing <> v_version.workingrevision THEN
        PERFORM tgsis.revision_set(v_version.versionid, v_viewing);  -- TG200 unless in its history
        RETURN v_viewing;
    END IF;
    IF NOT EXISTS (SELECT FROM tgsis.versioned_tables WHERE schemaname = 'tgsis' AND tablename = 'vrtx')
       OR current_setting('transaction_read_only')::boolean
       OR current_setting('transaction_isolation') <> 'read committed'
       OR NOT tgsis.has_version_privilege(v_name, 'write') THEN
        RETURN NULL;
    END IF;
    SELECT * INTO v_version FROM tgsis.versions WHERE versionid = v_version.versionid FOR UPDATE;
    IF NOT FOUND THEN
        RAISE EXCEPTION 'version % does not exist', quote_literal(v_name)
            USING ERRCODE = 'TG200', DETAIL = 'It was deleted while this check-out waited for it.';
    END IF;
    PERFORM tgsis.next_working_revision(v_version.versionid);
    RETURN v_version.workingrevision;
END
$$;

COMMENT ON FUNCTION tgsis.checkout_revision() IS
    'the frozen revision a check-out of the session''s version reads: the viewed older revision, else the working revision, frozen now (a new one starts; waits for open writers of the version); NULL without writing or locking when feature versioning is off, the transaction is read-only or not READ COMMITTED, or the role may not write in the version';

-- ==== core/restore_shipped_row.sql ====
-- tgsis.restore_shipped_row(): a restore's copy of a row the script ships replaces the shipped row.
-- On the extension route pg_dump dumps the catalog tables' rows
-- (core/config_dump.sql), and the CREATE EXTENSION of the restore has inserted
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

-- ==== core/config_dump.sql ====
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
                                      'tgsis.versioned_tables', 'tgsis.versioning_dropped',
                                      'tgsis.revision_seq', 'tgsis.versions_versionid_seq',
                                      'tgsis.versioning_dropped_id_seq'] LOOP
            PERFORM pg_catalog.pg_extension_config_dump(v_name::regclass, '');
        END LOOP;
    END IF;
END
$do$;

-- ==== core/grants.sql ====
-- Rights of the group roles on the objects of tgsis. Feature-class tables get
-- theirs from tgsis.register_feature_class.
GRANT USAGE ON SCHEMA tgsis TO tgsis_reader;
GRANT SELECT ON tgsis.error_codes, tgsis.installation, tgsis.property_types, tgsis.catalog TO tgsis_reader;
GRANT SELECT ON tgsis.class_tables TO tgsis_reader;
-- the registry of data models says only what tgsis is made of: anyone may read
-- it (the write path of every role consults it); only tgsis's owner writes it
GRANT SELECT ON tgsis.data_models, tgsis.model_tables TO PUBLIC;
-- (the storage tables get theirs from tgsis.create_storage)
-- versioning: readers see the version tree; editors create, save and delete
-- versions (per-version owner rights are enforced by the functions)
GRANT SELECT ON tgsis.versions, tgsis.revisions, tgsis.version_tree, tgsis.versioned_tables, tgsis.versioning_dropped,
                tgsis.conflicts, tgsis.version_privileges
    TO tgsis_reader;
-- the generated write triggers run as each table's owner and probe the locks
GRANT SELECT ON tgsis.object_locks TO PUBLIC;
-- version state changes only through the SECURITY DEFINER functions, which
-- check the caller's version rights (tgsis.has_version_privilege); the
-- helpers they share are theirs alone
REVOKE ALL ON FUNCTION tgsis.next_working_revision(integer, integer[], integer), tgsis.lock_for_merge(text, text),
                       tgsis.copy_object_state(text, text[], integer[], integer[], integer),
                       tgsis.update_shared_rows(tgsis.versioned_tables, text, text, text[], integer[], integer[], integer)
    FROM PUBLIC;
-- tgsis.catalog, versioned_tables and versioning_dropped are read-only too:
-- definer code acts on what they name (and EXECUTEs the recorded constraint
-- definitions), so only tgsis's definer functions write them, checking the
-- calling role and reading what they record from the system catalogs
GRANT EXECUTE ON FUNCTION tgsis.record_dropped(regclass, oid, boolean),
                          tgsis.register_versioned_table(regclass, text, text, integer, text, text, text, text[]),
                          tgsis.unregister_versioned_table(text, text), tgsis.forget_dropped(integer)
    TO tgsis_admin;
GRANT EXECUTE ON FUNCTION tgsis.enable_feature_versioning(), tgsis.disable_feature_versioning(boolean),
                          tgsis.compress_versions(boolean) TO tgsis_admin;
