-- Constraints and unique indexes that enable_versioning dropped because they
-- cannot hold across versions; disable_versioning restores each one as soon
-- as the tables it involves are plain tables again.
CREATE TABLE tgsis.versioning_dropped (
    id          integer GENERATED ALWAYS AS IDENTITY PRIMARY KEY,
    schemaname  text    NOT NULL,
    tablename   text    NOT NULL,
    name        text    NOT NULL,
    definition  text    NOT NULL,
    is_index    boolean NOT NULL DEFAULT false,
    refschema   text,
    reftable    text,
    dropped_for text    NOT NULL,
    dropped_at  timestamptz NOT NULL DEFAULT now()
);

COMMENT ON SEQUENCE tgsis.versioning_dropped_id_seq IS 'row ids of tgsis.versioning_dropped';
COMMENT ON TABLE tgsis.versioning_dropped IS
    'constraints and unique indexes dropped by enable_versioning (they cannot hold across versions), restored by disable_versioning';
COMMENT ON COLUMN tgsis.versioning_dropped.id IS 'row id';
COMMENT ON COLUMN tgsis.versioning_dropped.schemaname IS 'schema of the table that carried the constraint';
COMMENT ON COLUMN tgsis.versioning_dropped.tablename IS 'table that carried the constraint (its plain name)';
COMMENT ON COLUMN tgsis.versioning_dropped.name IS 'constraint or index name';
COMMENT ON COLUMN tgsis.versioning_dropped.definition IS 'pg_get_constraintdef / pg_get_indexdef text';
COMMENT ON COLUMN tgsis.versioning_dropped.is_index IS 'true: a unique index (definition is a CREATE INDEX statement)';
COMMENT ON COLUMN tgsis.versioning_dropped.refschema IS 'schema of the referenced table of a foreign key';
COMMENT ON COLUMN tgsis.versioning_dropped.reftable IS 'referenced table of a foreign key';
COMMENT ON COLUMN tgsis.versioning_dropped.dropped_for IS 'the table whose versioning dropped it';
COMMENT ON COLUMN tgsis.versioning_dropped.dropped_at IS 'when it was dropped';
