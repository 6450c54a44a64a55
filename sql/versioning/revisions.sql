-- Every revision and the version it belongs to. A revision is writable only
-- while it is its version's working revision; a named (saved) revision is
-- frozen for good.
CREATE TABLE tgsis.revisions (
    revision   integer     PRIMARY KEY CHECK (revision >= 0),
    versionid  integer     NOT NULL REFERENCES tgsis.versions (versionid) ON DELETE CASCADE,
    name       text,
    created_at timestamptz NOT NULL DEFAULT now(),
    created_by name        NOT NULL DEFAULT current_user,
    saved_at   timestamptz,
    visibleset integer[],
    UNIQUE (versionid, name),
    CONSTRAINT revisions_saved_named CHECK ((name IS NULL) = (saved_at IS NULL))
);

CREATE INDEX revisions_versionid_idx ON tgsis.revisions (versionid, revision);

COMMENT ON TABLE tgsis.revisions IS 'revisions: integer labels of groups of changes, each owned by one version';
COMMENT ON COLUMN tgsis.revisions.revision IS 'revision number (0: DEFAULT''s initial revision; others from tgsis.revision_seq)';
COMMENT ON COLUMN tgsis.revisions.versionid IS 'the version it belongs to';
COMMENT ON COLUMN tgsis.revisions.name IS 'name given by save_revision (NULL: not saved); unique within the version';
COMMENT ON COLUMN tgsis.revisions.created_at IS 'when the revision was handed out';
COMMENT ON COLUMN tgsis.revisions.created_by IS 'role whose call handed it out';
COMMENT ON COLUMN tgsis.revisions.saved_at IS 'when save_revision froze it (NULL: not saved)';
COMMENT ON COLUMN tgsis.revisions.visibleset IS
    'the revision set its version saw while it was the working revision, stored when it stopped being one (NULL while working): what goto_revision shows';
