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
