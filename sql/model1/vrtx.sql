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
