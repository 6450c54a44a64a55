-- tgsis.revision_objects: which objects of each versioned table have row versions written or closed in a revision.
-- Merge, refresh, conflict detection and delete_version ask "which objects
-- changed in these revisions"; answered from the storage itself, that is a
-- scan of every versioned table, growing with the database rather than with
-- the change (docs/performance.md, "Merges at 2M and 20M rows"). Each writer
-- of storage notes here the objects it writes in a revision, once per object
-- and revision: the views' INSTEAD OF triggers (tgsis.record_changed_objects,
-- after one index probe per row), the storage's AFTER INSERT statement
-- trigger for direct writes (tgsis.record_inserted_objects), and tgsis's own
-- set-based writers (tgsis.note_changed_objects). Readers take the listed
-- objects' rows by key and apply the same test as before, so a note is a
-- promise that nothing outside the notes changed, never the answer itself:
-- a note of an object whose rows went since is harmless. Revision 0 (the rows
-- enable_versioning found, and rows of features of no version) is never
-- noted: tgsis.changed_objects scans when asked about it.
-- No unique key: two sessions writing one object in one revision must not
-- wait for each other's note (they do not wait for each other's rows), so
-- each adds its own when it does not see one; readers take distinct keys.
CREATE TABLE tgsis.revision_objects (
    revision   integer NOT NULL CHECK (revision <> 0),
    schemaname text    NOT NULL,
    tablename  text    NOT NULL,
    objectkey  text    NOT NULL
);

CREATE INDEX revision_objects_idx ON tgsis.revision_objects (revision, schemaname, tablename, objectkey);

COMMENT ON TABLE tgsis.revision_objects IS
    'objects of versioned tables with row versions written or closed in a revision (one or more rows per revision, table and object), noted by every writer of storage; what merges, refreshes, conflict checks and delete_version read instead of scanning storage';
COMMENT ON INDEX tgsis.revision_objects_idx IS 'the objects noted in given revisions of one table, and the notes of a revision';
COMMENT ON COLUMN tgsis.revision_objects.revision IS 'the revision (never 0: tgsis.changed_objects scans storage for it)';
COMMENT ON COLUMN tgsis.revision_objects.schemaname IS 'schema of the versioned table (tgsis.versioned_tables.schemaname)';
COMMENT ON COLUMN tgsis.revision_objects.tablename IS 'the versioned table (tgsis.versioned_tables.tablename)';
COMMENT ON COLUMN tgsis.revision_objects.objectkey IS 'the object''s key (the table''s objectkeyfield) as text';

-- the generated write triggers of versioned views run as each table's owner and probe it
-- (as they probe tgsis.object_locks); only tgsis's functions write it
GRANT SELECT ON tgsis.revision_objects TO PUBLIC;
