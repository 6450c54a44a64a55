-- tgsis.create_model1_storage(): create the tables of model 1 (static 3D objects: vertices, simplices, atoms, parts) and register them.
-- Their geometry rows are the core's (geometry/storage.sql).
-- Called by tgsis.create_storage (storage/create_storage.sql says why the tables
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

-- the registry rows of model 1 (core/data_models.sql says why)
INSERT INTO tgsis.data_models (model, name, timemodel, geotypes, create_function, extent_function, check_function, description)
VALUES (1, 'static 3D objects', 'STATIC', '{MULTIPOINT,MULTILINESTRING,SURFACE,MULTITETRA,GEOMETRYCOLLECTION}',
        'create_model1_storage', 'static_extent', 'check_static_geometry',
        'objects that do not change in time: vertices and the simplices (points, segments, triangles, tetrahedra) that point at them');
-- (vertices and simplices are registered for chunks, docs/storage.md; atoms and parts stay rows)
INSERT INTO tgsis.model_tables (tablename, model, iudorder, geotype, description, chunkcolumn, chunkrefs, chunksize, chunkdefault) VALUES
    ('vrtx',    1, 1, NULL,              'a vertex of a static geometry',             'vrtxid',  '{}', 1024, true),
    ('point',   1, 2, 'MULTIPOINT',      'a point of a MULTIPOINT geometry',          'pointid', '{vrtxid1}', 1024, true),
    ('segment', 1, 2, 'MULTILINESTRING', 'a segment of a MULTILINESTRING geometry',   'segid',   '{vrtxid1,vrtxid2}', 1024, true),
    ('trgl',    1, 2, 'SURFACE',         'a triangle of a SURFACE geometry',          'trglid',  '{vrtxid1,vrtxid2,vrtxid3}', 1024, true),
    ('tetra',   1, 2, 'MULTITETRA',      'a tetrahedron of a MULTITETRA geometry',    'tetraid', '{vrtxid1,vrtxid2,vrtxid3,vrtxid4}', 1024, true),
    ('atom',    1, 2, NULL,              'a vertex repeating another one (GOCAD ATOM/PATOM)', NULL, '{}', NULL, false),
    ('part',    1, 2, NULL,              'a range of simplices forming a part (GOCAD TFACE/ILINE/TVOLUME)', NULL, '{}', NULL, false);
