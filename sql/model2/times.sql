-- Model 2 (surfaces at instants): the instants at which each surface is known.
-- Between two instants the surface is constant (a step function, left- or
-- right-closed as the query chooses); its shape at an instant is in
-- tgsis.times_vrtx and tgsis.times_trgl under the same (geoid, times).
CREATE TABLE tgsis.times (
    geoid bigint           NOT NULL,
    times double precision NOT NULL CHECK (times > '-Infinity' AND times < 'Infinity'),
    PRIMARY KEY (geoid, times)
);

COMMENT ON TABLE tgsis.times IS 'model 2: the instants t0 < t1 < ... at which a surface (tgsis.geometry, timemodel INSTANTS) is known';
COMMENT ON COLUMN tgsis.times.geoid IS 'geometry (tgsis.geometry.geoid)';
COMMENT ON COLUMN tgsis.times.times IS 'instant in model time (larger is later; unit in tgsis.catalog.timeunit)';
