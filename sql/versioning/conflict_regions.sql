-- The regions of conflicting meshes (issue 39, docs/merge.md): per object of
-- tgsis.conflicts that merges by region (a model-1 point set, line set,
-- surface or tetrahedral solid), the connected sets of vertices and cells the
-- two sides changed, as the three-way merge found them (tgsis.merge3), with
-- the solution of each. Found and recorded by the Python client
-- (tgsis.find_conflicts: numpy runs there), on the conflict's marks: a region
-- holds for the states it was found on, and tgsis.find_conflicts removes the
-- regions of an object either side changed again (their marks are stale).
-- A region changed on one side only, or on both alike, merges by itself
-- ('automatic'); the others need a solution (tgsis.resolve_region). A
-- surface at instants (model 2) merges per instant and an evolving surface
-- (model 3) per geometry instant of a topology period: its regions name
-- that slice (times; timem for the period) and are numbered through the
-- object's slices, so a region index names one region of the object. Rows are
-- written only by the SECURITY DEFINER functions; readers of conflicts read them.
CREATE TABLE tgsis.conflict_regions (
    versionid           integer     NOT NULL,
    objectclass         text        NOT NULL,
    objectkey           text        NOT NULL,
    region              integer     NOT NULL CHECK (region >= 0),
    childmark           text        NOT NULL,
    parentmark          text        NOT NULL,
    conflict            boolean     NOT NULL,
    changed_by          text        NOT NULL CHECK (changed_by IN ('parent', 'child', 'both')),
    vertex_ids          bigint[]    NOT NULL,
    cell_ids            bigint[]    NOT NULL,
    parent_vertex_ids   bigint[]    NOT NULL,
    parent_cell_ids     bigint[]    NOT NULL,
    child_vertex_ids    bigint[]    NOT NULL,
    child_cell_ids      bigint[]    NOT NULL,
    bbox                float8[]    CHECK (bbox IS NULL OR cardinality(bbox) = 6),
    parent_displacement float8      NOT NULL DEFAULT 0 CHECK (parent_displacement >= 0),
    child_displacement  float8      NOT NULL DEFAULT 0 CHECK (child_displacement >= 0),
    solution            text        NOT NULL DEFAULT 'unsolved'
                                    CHECK (solution IN ('unsolved', 'automatic', 'parent', 'child', 'base', 'average', 'manual')),
    solution_mesh       bytea,
    solved_at           timestamptz,
    solved_by           name,
    times               float8      CHECK (times > '-Infinity' AND times < 'Infinity'),
    timem               float8      CHECK (timem > '-Infinity' AND timem < 'Infinity'),
    -- the rows of an average or manual solution in a form SQL reads (the psql merge applies them:
    -- tgsis.merge_mesh_by_region), beside solution_mesh; NULL for a solution recorded with its .npz only
    solution_vertex_ids     bigint[],
    solution_vertices       float8[],
    solution_cell_ids       bigint[],
    solution_cells          bigint[],
    solution_vertex_columns text[],
    solution_vertex_values  float8[],
    solution_cell_columns   text[],
    solution_cell_values    float8[],
    PRIMARY KEY (versionid, objectclass, objectkey, region),
    FOREIGN KEY (versionid, objectclass, objectkey) REFERENCES tgsis.conflicts (versionid, objectclass, objectkey)
        ON DELETE CASCADE,
    CONSTRAINT conflict_regions_automatic CHECK ((solution = 'automatic') = (NOT conflict)),
    CONSTRAINT conflict_regions_mesh CHECK ((solution_mesh IS NOT NULL) = (solution IN ('average', 'manual'))),
    CONSTRAINT conflict_regions_solved CHECK ((solution IN ('unsolved', 'automatic')) = (solved_at IS NULL)),
    CONSTRAINT conflict_regions_slice CHECK (timem IS NULL OR times IS NOT NULL),
    -- the rows are all given or none, only with the .npz (a region of a slice: keyed by the slice's ids), each
    -- array of its rows' size
    CONSTRAINT conflict_regions_rows CHECK (
        num_nulls(solution_vertex_ids, solution_vertices, solution_cell_ids, solution_cells, solution_vertex_columns,
                  solution_vertex_values, solution_cell_columns, solution_cell_values) IN (0, 8)
        AND (solution_vertex_ids IS NULL OR (solution_mesh IS NOT NULL
             AND cardinality(solution_vertices) = 3 * cardinality(solution_vertex_ids)
             AND cardinality(solution_cells) % greatest(cardinality(solution_cell_ids), 1) = 0
             AND cardinality(solution_vertex_values)
                 = cardinality(solution_vertex_columns) * cardinality(solution_vertex_ids)
             AND cardinality(solution_cell_values) = cardinality(solution_cell_columns) * cardinality(solution_cell_ids))))
);

-- Per-class rights (docs/security.md) hold here as at the model tables: a region holds vertex and cell
-- ids, a box and, solved average or manual, the rows of a feature's mesh, so a role sees the regions of
-- features of the classes it may read only (tgsis.class_denied_geoids, as the model tables' policies).
-- The definer functions that write the table run as its owner, whom the policy spares.
ALTER TABLE tgsis.conflict_regions ENABLE ROW LEVEL SECURITY;
CREATE POLICY tgsis_class_read ON tgsis.conflict_regions FOR SELECT
    USING (CASE WHEN objectclass = 'feature'
                THEN objectkey::bigint NOT IN (SELECT tgsis.class_denied_geoids('SELECT', current_user))
                ELSE true END);
COMMENT ON POLICY tgsis_class_read ON tgsis.conflict_regions IS
    'per-class rights: the regions of features of classes the role may not SELECT are not seen (tgsis.class_denied_geoids)';

COMMENT ON TABLE tgsis.conflict_regions IS
    'regions of the conflicting meshes of versions (the three-way merge by region, docs/merge.md), found on the conflict''s marks, with the solution of each (tgsis.find_conflicts in Python, tgsis.resolve_region)';
COMMENT ON COLUMN tgsis.conflict_regions.versionid IS 'the child version';
COMMENT ON COLUMN tgsis.conflict_regions.objectclass IS 'object class of the conflicting object (feature)';
COMMENT ON COLUMN tgsis.conflict_regions.objectkey IS 'object key (as text: the feature''s geoid)';
COMMENT ON COLUMN tgsis.conflict_regions.region IS 'index of the region in the merge (0-based), as tgsis.merge3 numbers them';
COMMENT ON COLUMN tgsis.conflict_regions.childmark IS 'the conflict''s childmark the region was found on (another one: the region is stale and removed)';
COMMENT ON COLUMN tgsis.conflict_regions.parentmark IS 'the conflict''s parentmark the region was found on';
COMMENT ON COLUMN tgsis.conflict_regions.conflict IS 'true: both sides changed the region to different rows, it needs a solution; false: it merges by itself';
COMMENT ON COLUMN tgsis.conflict_regions.changed_by IS 'parent, child or both: the sides that changed the region';
COMMENT ON COLUMN tgsis.conflict_regions.vertex_ids IS 'every vertex id of the region, its one-ring margin included, ascending (merged numbering)';
COMMENT ON COLUMN tgsis.conflict_regions.cell_ids IS 'every cell id of the region, its one-ring margin included, ascending';
COMMENT ON COLUMN tgsis.conflict_regions.parent_vertex_ids IS 'vertex ids of the region the parent changed (moved, added, removed, values)';
COMMENT ON COLUMN tgsis.conflict_regions.parent_cell_ids IS 'cell ids of the region the parent changed';
COMMENT ON COLUMN tgsis.conflict_regions.child_vertex_ids IS 'vertex ids of the region the version changed (its new ids renumbered as the merge does)';
COMMENT ON COLUMN tgsis.conflict_regions.child_cell_ids IS 'cell ids of the region the version changed';
COMMENT ON COLUMN tgsis.conflict_regions.bbox IS '{xmin,ymin,zmin,xmax,ymax,zmax} of the region in the three states (stored z), or NULL';
COMMENT ON COLUMN tgsis.conflict_regions.parent_displacement IS 'largest distance a vertex of the region moved in the parent';
COMMENT ON COLUMN tgsis.conflict_regions.child_displacement IS 'largest distance a vertex of the region moved in the version';
COMMENT ON COLUMN tgsis.conflict_regions.solution IS 'unsolved, automatic (no conflict: merges by itself), parent, child, base (that state''s rows of the region), average (the average shape of the two sides), manual (a mesh given)';
COMMENT ON COLUMN tgsis.conflict_regions.solution_mesh IS 'average and manual: the region''s rows, an .npz of a tgsis.merge3.MeshState (read without pickles)';
COMMENT ON COLUMN tgsis.conflict_regions.solved_at IS 'when the solution was recorded';
COMMENT ON COLUMN tgsis.conflict_regions.solved_by IS 'role that recorded it';
COMMENT ON COLUMN tgsis.conflict_regions.times IS 'the slice of a temporal surface the region lies in: the instant (tgsis.times, model 2) or the geometry instant (tgsis.timet, model 3); NULL for a model-1 mesh';
COMMENT ON COLUMN tgsis.conflict_regions.solution_vertex_ids IS 'average and manual (models 1 and 2, recorded by the Python client): the vertex ids of the solution''s rows (those of solution_mesh), ascending; NULL: the .npz only (the psql merge refuses it)';
COMMENT ON COLUMN tgsis.conflict_regions.solution_vertices IS 'their coordinates, x, y, z per vertex in the order of solution_vertex_ids';
COMMENT ON COLUMN tgsis.conflict_regions.solution_cell_ids IS 'the cell ids of the solution''s rows, ascending';
COMMENT ON COLUMN tgsis.conflict_regions.solution_cells IS 'their vertex ids, k per cell in the order of solution_cell_ids';
COMMENT ON COLUMN tgsis.conflict_regions.solution_vertex_columns IS 'the vertex properties of the solution (scalar ones; refid: the GOCAD atoms)';
COMMENT ON COLUMN tgsis.conflict_regions.solution_vertex_values IS 'their values, one per column per vertex (row after row), NaN for none';
COMMENT ON COLUMN tgsis.conflict_regions.solution_cell_columns IS 'the cell properties of the solution (scalar ones; part: the part runs)';
COMMENT ON COLUMN tgsis.conflict_regions.solution_cell_values IS 'their values, one per column per cell (row after row), NaN for none';
COMMENT ON COLUMN tgsis.conflict_regions.timem IS 'model 3: the topology period (tgsis.timem) of the region''s geometry instant; NULL otherwise';
