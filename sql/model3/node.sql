-- Model 3: the nodes (abstract vertices) of each topology period. Node ids
-- are unique within their geometry (the write path numbers them on through
-- the periods), so a node belongs to one period.
CREATE TABLE tgsis.node (
    geoid  bigint           NOT NULL,
    timem  double precision NOT NULL,
    nodeid bigint           NOT NULL,
    PRIMARY KEY (geoid, timem, nodeid)
);

COMMENT ON TABLE tgsis.node IS 'model 3: nodes (vertices of the topology) of each topology period';
COMMENT ON COLUMN tgsis.node.geoid IS 'geometry (tgsis.geometry.geoid)';
COMMENT ON COLUMN tgsis.node.timem IS 'the topology period (tgsis.timem.timem)';
COMMENT ON COLUMN tgsis.node.nodeid IS 'node id, unique within the geometry; _idx of VERTEX-aligned properties';
