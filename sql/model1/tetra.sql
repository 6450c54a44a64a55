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
