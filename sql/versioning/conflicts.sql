-- Conflicting objects of versions (the thesis' CONFLICT table): objects
-- changed both in a version and in its parent since the version's base.
-- A solution holds for the state it was given on: find_conflicts sets it
-- back to 'unsolved' when either side changes the object again (the marks).
CREATE TABLE tgsis.conflicts (
    versionid    integer     NOT NULL REFERENCES tgsis.versions (versionid) ON DELETE CASCADE,
    objectclass  text        NOT NULL,
    objectkey    text        NOT NULL,
    conflicttype text[]      NOT NULL,
    childtables  text[]      NOT NULL,
    parenttables text[]      NOT NULL,
    childmark    text        NOT NULL,
    parentmark   text        NOT NULL,
    solution     text        NOT NULL DEFAULT 'unsolved'
                             CHECK (solution IN ('unsolved', 'parent', 'child', 'manual')),
    detected_at  timestamptz NOT NULL DEFAULT now(),
    solved_at    timestamptz,
    solved_by    name,
    PRIMARY KEY (versionid, objectclass, objectkey),
    CONSTRAINT conflicts_solved CHECK ((solution = 'unsolved') = (solved_at IS NULL))
);

COMMENT ON TABLE tgsis.conflicts IS
    'objects changed both in a version and in its parent since the version''s base, with their solutions (tgsis.find_conflicts, tgsis.resolve_conflict)';
COMMENT ON COLUMN tgsis.conflicts.versionid IS 'the child version';
COMMENT ON COLUMN tgsis.conflicts.objectclass IS 'object class of the object';
COMMENT ON COLUMN tgsis.conflicts.objectkey IS 'object key (as text)';
COMMENT ON COLUMN tgsis.conflicts.conflicttype IS 'short names of the tables changed on both sides (empty: the sides changed different tables of the object)';
COMMENT ON COLUMN tgsis.conflicts.childtables IS 'short names of the tables the version changed';
COMMENT ON COLUMN tgsis.conflicts.parenttables IS 'short names of the tables the parent changed';
COMMENT ON COLUMN tgsis.conflicts.childmark IS 'fingerprint of the version''s changes to the object (a later change unsolves the conflict)';
COMMENT ON COLUMN tgsis.conflicts.parentmark IS 'fingerprint of the parent''s changes to the object (a later change unsolves the conflict)';
COMMENT ON COLUMN tgsis.conflicts.solution IS 'unsolved, parent (keep the parent''s object), child (take the version''s), manual (the version holds a merged object)';
COMMENT ON COLUMN tgsis.conflicts.detected_at IS 'when the conflict was first found';
COMMENT ON COLUMN tgsis.conflicts.solved_at IS 'when the solution was recorded';
COMMENT ON COLUMN tgsis.conflicts.solved_by IS 'role that recorded it';
