-- Model 3: the triangles of each topology period, pointing at its nodes.
-- They stay the same through the period while the nodes move.
CREATE TABLE tgsis.d4dtrgl (
    geoid   bigint           NOT NULL,
    timem   double precision NOT NULL,
    trglid  bigint           NOT NULL,
    nodeid1 bigint           NOT NULL,
    nodeid2 bigint           NOT NULL,
    nodeid3 bigint           NOT NULL,
    CONSTRAINT d4dtrgl_distinct_nodes CHECK (nodeid1 <> nodeid2 AND nodeid1 <> nodeid3 AND nodeid2 <> nodeid3),
    PRIMARY KEY (geoid, timem, trglid)
);

COMMENT ON TABLE tgsis.d4dtrgl IS 'model 3: triangles of each topology period of an evolving surface';
COMMENT ON COLUMN tgsis.d4dtrgl.geoid IS 'geometry (tgsis.geometry.geoid)';
COMMENT ON COLUMN tgsis.d4dtrgl.timem IS 'the topology period (tgsis.timem.timem)';
COMMENT ON COLUMN tgsis.d4dtrgl.trglid IS 'triangle id, unique within the geometry; _idx of CELL-aligned properties';
COMMENT ON COLUMN tgsis.d4dtrgl.nodeid1 IS 'node 1 (tgsis.node.nodeid of the same geoid and period)';
COMMENT ON COLUMN tgsis.d4dtrgl.nodeid2 IS 'node 2 (tgsis.node.nodeid of the same geoid and period)';
COMMENT ON COLUMN tgsis.d4dtrgl.nodeid3 IS 'node 3 (tgsis.node.nodeid of the same geoid and period)';
