-- Rights on versions beyond ownership. A version's owner (the role that
-- created it) and members of tgsis_admin hold every right on it; other roles
-- hold what is granted here, to them or to a role they are members of
-- ('public': everybody). DEFAULT starts writable by tgsis_editor, who may
-- also create children of it; merging into DEFAULT is left to tgsis_admin.
CREATE TABLE tgsis.version_privileges (
    versionid  integer     NOT NULL REFERENCES tgsis.versions (versionid) ON DELETE CASCADE,
    grantee    name        NOT NULL,
    privilege  text        NOT NULL CHECK (privilege IN ('write', 'create', 'merge', 'delete')),
    granted_by name        NOT NULL,
    granted_at timestamptz NOT NULL DEFAULT now(),
    PRIMARY KEY (versionid, grantee, privilege)
);

INSERT INTO tgsis.version_privileges (versionid, grantee, privilege, granted_by)
VALUES (0, 'tgsis_editor', 'write', current_user), (0, 'tgsis_editor', 'create', current_user);

COMMENT ON TABLE tgsis.version_privileges IS
    'rights on versions granted to roles other than the version''s owner and tgsis_admin (who hold them all)';
COMMENT ON COLUMN tgsis.version_privileges.versionid IS 'the version';
COMMENT ON COLUMN tgsis.version_privileges.grantee IS 'role granted the right (its members have it too); public: every role';
COMMENT ON COLUMN tgsis.version_privileges.privilege IS
    'write: change rows, save revisions, resolve conflicts, refresh, lock objects; create: create child versions; merge: merge a child into this version; delete: delete this version';
COMMENT ON COLUMN tgsis.version_privileges.granted_by IS 'role that granted it';
COMMENT ON COLUMN tgsis.version_privileges.granted_at IS 'when it was granted';
