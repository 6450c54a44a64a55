-- Model 3: the geometry instants of each topology period. The first is the
-- period's start; the last of a period that is not the last is the next
-- period's start (both periods hold a shape at that instant).
CREATE TABLE tgsis.timet (
    geoid bigint           NOT NULL,
    timem double precision NOT NULL,
    timet double precision NOT NULL CHECK (timet > '-Infinity' AND timet < 'Infinity'),
    CONSTRAINT timet_within_period CHECK (timet >= timem),
    PRIMARY KEY (geoid, timem, timet)
);

COMMENT ON TABLE tgsis.timet IS 'model 3: geometry instants of each topology period; node positions are known there and linear in between';
COMMENT ON COLUMN tgsis.timet.geoid IS 'geometry (tgsis.geometry.geoid)';
COMMENT ON COLUMN tgsis.timet.timem IS 'the topology period (tgsis.timem.timem)';
COMMENT ON COLUMN tgsis.timet.timet IS 'geometry instant, >= timem';
