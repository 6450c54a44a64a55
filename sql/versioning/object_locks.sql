-- Object locks (as Workspace Manager's LockRows): a version takes an object
-- so that no other version (sibling, parent, child) can change it until the
-- lock is released; with exclusive, only the role that took it may change it
-- in that version. One lock per object across the whole tree. Locks go with
-- their version when it is deleted.
CREATE TABLE tgsis.object_locks (
    objectclass text        NOT NULL,
    objectkey   text        NOT NULL,
    versionid   integer     NOT NULL REFERENCES tgsis.versions (versionid) ON DELETE CASCADE,
    exclusive   boolean     NOT NULL DEFAULT false,
    locked_by   name        NOT NULL,
    locked_at   timestamptz NOT NULL DEFAULT now(),
    PRIMARY KEY (objectclass, objectkey)
);

CREATE INDEX object_locks_versionid_idx ON tgsis.object_locks (versionid);

COMMENT ON TABLE tgsis.object_locks IS
    'objects locked by a version: writes to them in any other version fail with TG303 (and, for exclusive locks, writes by other roles in that version)';
COMMENT ON COLUMN tgsis.object_locks.objectclass IS 'object class of the object (tgsis.versioned_tables.objectclass)';
COMMENT ON COLUMN tgsis.object_locks.objectkey IS 'object key, as text';
COMMENT ON COLUMN tgsis.object_locks.versionid IS 'the version holding the lock: the only one whose writes may change the object';
COMMENT ON COLUMN tgsis.object_locks.exclusive IS 'also keep other roles from changing the object in the holding version';
COMMENT ON COLUMN tgsis.object_locks.locked_by IS 'role that took the lock';
COMMENT ON COLUMN tgsis.object_locks.locked_at IS 'when the lock was taken';
