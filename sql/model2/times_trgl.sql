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
