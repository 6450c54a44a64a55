-- The SQLSTATEs tgsis raises. Class TG is ours (SQL reserves classes starting
-- with I-Z for implementations; PostgreSQL uses none of them). The second
-- character of the subclass says the area, see docs/errors.md. The Python
-- client maps each row to an exception class (tgsis.errors); a test keeps
-- this table, the Python classes and docs/errors.md in step.
CREATE TABLE tgsis.error_codes (
    sqlstate    char(5) PRIMARY KEY CHECK (sqlstate ~ '^TG[0-9A-Z]{3}$'),
    name        text    NOT NULL UNIQUE CHECK (name ~ '^[a-z][a-z0-9_]*$'),
    area        text    NOT NULL CHECK (area IN ('core', 'input', 'catalog', 'versioning', 'time', 'mesh')),
    description text    NOT NULL
);

COMMENT ON TABLE tgsis.error_codes IS
    'SQLSTATEs raised by tgsis (class TG); the Python client maps each to an exception class';
COMMENT ON COLUMN tgsis.error_codes.sqlstate IS 'five-character SQLSTATE, always TGxxx';
COMMENT ON COLUMN tgsis.error_codes.name IS 'condition name; the Python class is its CamelCase form plus "Error"';
COMMENT ON COLUMN tgsis.error_codes.area IS 'part of tgsis that raises it: core, input, catalog, versioning, time or mesh';
COMMENT ON COLUMN tgsis.error_codes.description IS 'when the error is raised';

INSERT INTO tgsis.error_codes (sqlstate, name, area, description) VALUES
    ('TG000', 'tgsis',            'core',    'a tgsis error that fits no narrower code'),
    ('TG001', 'installation',     'core',    'the tgsis objects in the database cannot be installed, upgraded or used at this version'),
    ('TG002', 'missing_privilege','core',    'the current role lacks a right tgsis needs (creating roles, owning a version, merging into DEFAULT)'),
    ('TG003', 'concurrent_read',  'core',    'a read of several statements in a READ COMMITTED transaction met other sessions'' commits between its statements at every try: its statements would have seen different states'),
    ('TG100', 'invalid_input',    'input',   'an argument is out of range, NULL where a value is required, or otherwise malformed'),
    ('TG101', 'invalid_name',     'input',   'a name (feature class, property, version, table) is empty, too long, or would need quoting where that is not allowed'),
    ('TG102', 'invalid_geometry', 'input',   'coordinates are NaN or infinite, or a simplex has out-of-range or repeated vertex indices'),
    ('TG103', 'invalid_property', 'input',   'a property has an unknown name, a type outside the allowed list, or the wrong number of values'),
    ('TG104', 'invalid_g_map',    'input',   'arrays that are no valid n-G-map (an alpha_i that is not an involution, a fixed point below alpha_n, alpha_i o alpha_j not an involution for i + 2 <= j, a dart whose alpha_i lies in another topology period), or a G-map an operation cannot take; reserved for models 4 and 5'),
    ('TG200', 'not_found',        'catalog', 'a named object (feature class, feature, geometry, table) does not exist'),
    ('TG201', 'already_exists',   'catalog', 'an object with that name or key exists already'),
    ('TG202', 'in_use',           'catalog', 'an object cannot be dropped or changed while others depend on it'),
    ('TG203', 'unknown_data_model', 'catalog', 'a geometry or feature class of a data model that a function has no rule for, or that tgsis.data_models does not register'),
    ('TG204', 'discontinuous_periods', 'catalog', 'a topology period of an evolving surface or G-map (models 3, 4) whose first shape lies farther than the tolerance from the last shape of the period before: a snapshot would jump there'),
    ('TG300', 'versioning',       'versioning', 'a versioning error that fits no narrower code'),
    ('TG301', 'read_only_revision', 'versioning', 'a write while the session views an older revision, or into a frozen (saved) revision'),
    ('TG302', 'unsolved_conflicts', 'versioning', 'a merge or refresh while objects changed on both sides have no recorded solution'),
    ('TG303', 'object_locked',    'versioning', 'a write (or merge) would change an object another version, or another role, holds a lock on'),
    ('TG304', 'checkout_conflict', 'versioning', 'a check-in of an object that another writer changed (or deleted) since it was checked out'),
    ('TG305', 'not_versioned',    'versioning', 'a write in a version other than DEFAULT (or at an older revision) to tables that are not versioned, or to features of a class without versioning: it would land in DEFAULT, which every version sees'),
    ('TG306', 'unsupported_view_statement', 'versioning', 'a statement through a versioned view that the view cannot write as a plain table would: an INSERT whose conflict clause (DO NOTHING, DO UPDATE) meets a row that is there, or a change of the session''s version, revision or role inside an UPDATE of the view'),
    ('TG307', 'region_solution',  'versioning', 'a solution the regions of a conflicting mesh refuse: for a region that is no conflict (it merges by itself), for regions found on a state either side changed since (find them again), or a whole side of an object that would drop the other side''s edits in regions that are no conflict'),
    ('TG308', 'period_topology',  'versioning', 'a merge by region of an evolving surface (model 3) refused: the merged meshes of the geometry instants of one topology period would not share one topology (nodes and triangles), which a period must');
