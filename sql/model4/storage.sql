-- tgsis.create_model4_storage(): create the tables of model 4 (n-G-maps in R^m evolving in valid time) and register them.
-- The spec's relations (feature, timem, timet, node, vertex, dart, alpha,
-- abstractcell) with the names prefixed gmap_ where model 3 has the same
-- ones; a feature is its tgsis.geometry row (geotype and time model GMAP,
-- alive) with the G-map's dimensions in tgsis.gmap. Times are keys as in
-- model 3 (a period is its start timem, an instant its value timet).
-- Called by tgsis.create_storage (storage/create_storage.sql says why the
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

-- the registry rows of model 4 (core/data_models.sql says why)
INSERT INTO tgsis.data_models (model, name, timemodel, geotypes, timekey, cell_levels, create_function, extent_function,
                               check_function, description)
VALUES (4, 'generalized maps in time', 'GMAP', '{GMAP}',
        '[{"name": "_timem", "comment": "topology period (its start, tgsis.gmap_timem) the values belong to"},
          {"name": "_timet", "comment": "geometry instant (tgsis.gmap_timet of the period) the values belong to; values are linear in between"}]',
        true, 'create_model4_storage', 'gmap_extent', 'check_gmap_geometry',
        'n-dimensional objects with explicit topology (n-G-maps) embedded in R^m, with topology periods and points moving linearly between geometry instants');
-- (the darts and the involutions are registered for chunks by dartid, keyed (geoid, chunk) and (geoid, chunk,
-- level): docs/storage.md, "G-maps (models 4 and 5)"; stored as rows until tgsis.store_in_chunks switches them:
-- chunkdefault false. The node and the dart partner are vertex-id columns (refs, relative to the chunk's
-- smallest); a dart's acellid and positive may be NULL: arrays of their own type, holes marked by holes. The
-- instants, nodes and cells stay rows. The positions are registered for chunks by nodeid, keyed (geoid, timem,
-- timet, chunk), a 2-D float8 array per chunk (slots x m: the role 'point'), stored as rows until switched too.)
INSERT INTO tgsis.model_tables (tablename, model, iudorder, description, chunkcolumn, chunkrefs, chunksize, chunkdefault) VALUES
    ('gmap',        4, 1, 'the dimensions of a G-map', NULL, '{}', NULL, false),
    ('gmap_timem',  4, 1, 'a topology instant (start of a topology period) of a G-map', NULL, '{}', NULL, false),
    ('gmap_timet',  4, 2, 'a geometry instant of a topology period', NULL, '{}', NULL, false),
    ('gmap_node',   4, 2, 'a point of the embedding of a topology period', NULL, '{}', NULL, false),
    ('gmap_vertex', 4, 2, 'the position of a node at a geometry instant', 'nodeid', '{}', 1024, false),
    ('gmap_dart',   4, 2, 'a dart of a topology period', 'dartid', '{nodeid}', 1024, false),
    ('gmap_alpha',  4, 2, 'the image of a dart under one involution', 'dartid', '{dartid2}', 1024, false),
    ('gmap_cell',   4, 2, 'an abstract cell of the property level', NULL, '{}', NULL, false);
