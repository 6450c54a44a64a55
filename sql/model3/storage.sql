-- tgsis.create_model3_storage(): create the tables of model 3 (continuously evolving surfaces: topology and geometry instants, nodes, 4D triangles and vertices) and register them.
-- Called by tgsis.create_storage (storage/create_storage.sql says why the tables
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

-- the registry rows of model 3 (core/data_models.sql says why)
INSERT INTO tgsis.data_models (model, name, timemodel, geotypes, timekey, create_function, extent_function, check_function,
                               description, merge_function)
VALUES (3, 'continuously evolving surfaces', 'EVOLVING', '{SURFACE}',
        '[{"name": "_timem", "comment": "topology period (its start, tgsis.timem) the values belong to"},
          {"name": "_timet", "comment": "geometry instant (tgsis.timet of the period) the values belong to; values are linear in between"}]',
        'create_model3_storage', 'evolving_extent', 'check_temporal_geometry',
        'surfaces whose nodes move linearly between geometry instants, with topology periods',
        'merge_periods_by_slice');
-- (the triangles and node positions are registered for chunks, keyed (geoid, timem, chunk) and
-- (geoid, timem, timet, chunk): docs/storage.md, "Snapshots at t"; stored as rows until tgsis.store_in_chunks
-- switches them: chunkdefault false; the instants timem/timet and the nodes stay rows: a node row is its key
-- only, and a chunk holds at least one array that numbers its slots)
INSERT INTO tgsis.model_tables (tablename, model, iudorder, description, chunkcolumn, chunkrefs, chunksize, chunkdefault) VALUES
    ('timem',   3, 1, 'a topology instant (start of a topology period) of an evolving surface', NULL, '{}', NULL, false),
    ('timet',   3, 2, 'a geometry instant of a topology period', NULL, '{}', NULL, false),
    ('node',    3, 2, 'a node (vertex of the topology) of a topology period', NULL, '{}', NULL, false),
    ('d4dtrgl', 3, 2, 'a triangle of a topology period', 'trglid', '{nodeid1,nodeid2,nodeid3}', 1024, false),
    ('d4dvrtx', 3, 2, 'the position of a node at a geometry instant of its period', 'nodeid', '{}', 1024, false);
