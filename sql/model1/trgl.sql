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
