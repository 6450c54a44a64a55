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
