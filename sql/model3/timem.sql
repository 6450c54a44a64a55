-- Model 3 (continuously evolving surfaces): the instants TM at which a
-- surface's topology is (re)defined. Each starts a topology period that
-- lasts until the next one (the last: until its last geometry instant, or for
-- ever if the geometry is alive).
CREATE TABLE tgsis.timem (
    geoid bigint           NOT NULL,
    timem double precision NOT NULL CHECK (timem > '-Infinity' AND timem < 'Infinity'),
    PRIMARY KEY (geoid, timem)
);

COMMENT ON TABLE tgsis.timem IS 'model 3: topology instants t0 < ... < tk of an evolving surface (tgsis.geometry, timemodel EVOLVING)';
COMMENT ON COLUMN tgsis.timem.geoid IS 'geometry (tgsis.geometry.geoid)';
COMMENT ON COLUMN tgsis.timem.timem IS 'instant where the topology is (re)defined; starts a topology period';
