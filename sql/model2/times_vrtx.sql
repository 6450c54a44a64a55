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
