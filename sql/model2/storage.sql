-- tgsis.create_model2_storage(): create the tables of model 2 (surfaces at instants: instants, vertices and triangles per instant) and register them.
-- Called by tgsis.create_storage (storage/create_storage.sql says why the tables
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

-- the registry rows of model 2 (core/data_models.sql says why)
INSERT INTO tgsis.data_models (model, name, timemodel, geotypes, timekey, create_function, extent_function, check_function,
                               description, merge_function)
VALUES (2, 'surfaces at instants', 'INSTANTS', '{SURFACE}',
        '[{"name": "_times", "comment": "instant (model time) the values belong to: one of tgsis.times of the feature"}]',
        'create_model2_storage', 'instants_extent', 'check_temporal_geometry',
        'surfaces known at instants t0 < t1 < ..., constant in between (a shape per instant)',
        'merge_instants_by_slice');
-- (the vertices and triangles at an instant are registered for chunks, keyed (geoid, times, chunk): docs/storage.md,
-- "Snapshots at t"; stored in chunks by default in a new database, as model 1 is (chunkdefault: tgsis.create_storage
-- switches them unless tgsis.storage is rows); an upgraded database keeps its existing time tables as rows)
INSERT INTO tgsis.model_tables (tablename, model, iudorder, description, chunkcolumn, chunkrefs, chunksize, chunkdefault) VALUES
    ('times',      2, 1, 'an instant at which a surface is known', NULL, '{}', NULL, false),
    ('times_vrtx', 2, 2, 'a vertex of a surface at one of its instants', 'vrtxid', '{}', 1024, true),
    ('times_trgl', 2, 2, 'a triangle of a surface at one of its instants', 'trglid', '{vrtxid1,vrtxid2,vrtxid3}', 1024, true);
