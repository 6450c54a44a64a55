-- tgsis.class_tables: every table of every feature class, one row each, in creation order.
-- A class has a feature table, a cell-property table, possibly a table of the
-- properties of its other alignment and, if temporal, a per-instant property
-- table (tgsis.catalog names them in four columns). Versioning, deletion and
-- the checks of what may be versioned read this view instead of naming the
-- four columns each, so a table a class gains later is added here once.
CREATE VIEW tgsis.class_tables AS
SELECT c.classname, c.schemaname, t.tablename, t.kind, t.position
  FROM tgsis.catalog c
 CROSS JOIN LATERAL (VALUES (c.featuretable, 'feature', 1),
                            (c.cellprotable, 'cell', 2),
                            (c.otherprotable, 'other', 3),
                            (c.protablename, 'instant', 4)) AS t (tablename, kind, position)
 WHERE t.tablename IS NOT NULL;

COMMENT ON VIEW tgsis.class_tables IS
    'the tables of each feature class (tgsis.catalog): feature (one row per feature), cell (cell or vertex properties), other (properties of the other alignment), instant (per-instant properties of temporal classes), keyed by _geoid';
COMMENT ON COLUMN tgsis.class_tables.classname IS 'the feature class (tgsis.catalog.classname)';
COMMENT ON COLUMN tgsis.class_tables.schemaname IS 'schema of the table';
COMMENT ON COLUMN tgsis.class_tables.tablename IS 'the table';
COMMENT ON COLUMN tgsis.class_tables.kind IS 'feature, cell, other or instant';
COMMENT ON COLUMN tgsis.class_tables.position IS 'creation order within the class: 1 feature, 2 cell, 3 other, 4 instant (children after the feature table)';
