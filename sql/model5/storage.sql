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
    -- partial: an extent with a NaN (measured so before 0.3.0, kept in a versioned database) would spoil the index's
    -- inner boxes (tgsis.cube_has_nan says why); it is in no box query (tgsis.md_in_box carries the predicate)
    CREATE INDEX md_gmap_extent_idx ON tgsis.md_gmap USING gist (extent) WHERE NOT tgsis.cube_has_nan(extent);

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
    -- points of an object inside a box over any of its axes (the other axes unbounded); partial: a point with a
    -- NaN coordinate is in no box, and its key would spoil the index's inner boxes (the cube type's least and
    -- greatest of a NaN are the other operand's, by order of the comparison), so that an index scan missed valid
    -- points a sequential scan found (docs/storage.md, "NaN coordinates and the box indexes");
    -- tgsis.md_vertices_in_box carries the same predicate
    CREATE INDEX md_vertex_point_idx ON tgsis.md_vertex USING gist (cube(coordinate))
        WHERE NOT 'NaN'::double precision = ANY (coordinate);

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

-- the registry rows of model 5 (core/data_models.sql says why)
INSERT INTO tgsis.data_models (model, name, timemodel, geotypes, cell_levels, create_function, extent_function,
                               check_function, description)
VALUES (5, 'multiply indexed G-maps', 'MULTIDIM', '{GMAP}', true, 'create_model5_storage', 'md_extent', 'check_md_geometry',
        'n-G-maps in R^m whose extra axes are time, knowledge, scale or uncertainty (a surface over knowledge is a volume)');
-- (the darts and the involutions are registered for chunks by dartid as model 4's: model4/storage.sql; the
-- points by vrtxid, a 2-D float8 array per chunk (slots x m: the role 'point', docs/storage.md, "The points in
-- chunks"); all stored as rows until tgsis.store_in_chunks switches them)
INSERT INTO tgsis.model_tables (tablename, model, iudorder, description, chunkcolumn, chunkrefs, chunksize, chunkdefault) VALUES
    ('md_gmap',   5, 1, 'the dimensions, axes and extent of a multiply indexed G-map', NULL, '{}', NULL, false),
    ('md_vertex', 5, 2, 'a point in R^m', 'vrtxid', '{}', 1024, false),
    ('md_dart',   5, 2, 'a dart', 'dartid', '{vrtxid}', 1024, false),
    ('md_alpha',  5, 2, 'the image of a dart under one involution', 'dartid', '{dartid2}', 1024, false),
    ('md_cell',   5, 2, 'a cell of the property level', NULL, '{}', NULL, false);
