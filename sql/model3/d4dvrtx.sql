-- Model 3: node positions at each geometry instant of their period. Between
-- two geometry instants a node moves on the straight line between them.
CREATE TABLE tgsis.d4dvrtx (
    geoid  bigint           NOT NULL,
    timem  double precision NOT NULL,
    timet  double precision NOT NULL,
    nodeid bigint           NOT NULL,
    x      double precision NOT NULL,
    y      double precision NOT NULL,
    z      double precision NOT NULL,
    PRIMARY KEY (geoid, timem, timet, nodeid)
);

COMMENT ON TABLE tgsis.d4dvrtx IS 'model 3: position of every node at every geometry instant of its period (4D vertices)';
COMMENT ON COLUMN tgsis.d4dvrtx.geoid IS 'geometry (tgsis.geometry.geoid)';
COMMENT ON COLUMN tgsis.d4dvrtx.timem IS 'the topology period (tgsis.timem.timem)';
COMMENT ON COLUMN tgsis.d4dvrtx.timet IS 'the geometry instant (tgsis.timet.timet of the period)';
COMMENT ON COLUMN tgsis.d4dvrtx.nodeid IS 'the node (tgsis.node.nodeid)';
COMMENT ON COLUMN tgsis.d4dvrtx.x IS 'x coordinate at timet (unit of the class''s SRS)';
COMMENT ON COLUMN tgsis.d4dvrtx.y IS 'y coordinate at timet';
COMMENT ON COLUMN tgsis.d4dvrtx.z IS 'z coordinate at timet (up positive)';
