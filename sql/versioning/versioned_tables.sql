-- Tables registered for versioning (the thesis' VERSIONEDTABLE). A registered
-- table <t> is stored in <t>_ver and read and written through the view <t>.
CREATE TABLE tgsis.versioned_tables (
    schemaname          text     NOT NULL,
    tablename           text     NOT NULL,
    shortname           text     NOT NULL,
    objectkeyfield      text     NOT NULL,
    objectclass         text     NOT NULL,
    iudorder            integer  NOT NULL,
    keycolumns          text[]   NOT NULL,
    pkeyname            text     NOT NULL,
    tablecomment        text,
    identity_always     text[]   NOT NULL DEFAULT '{}',
    enabled_at          timestamptz NOT NULL DEFAULT now(),
    enabled_by          name     NOT NULL DEFAULT current_user,
    PRIMARY KEY (schemaname, tablename),
    UNIQUE (objectclass, shortname)
);

COMMENT ON TABLE tgsis.versioned_tables IS
    'tables registered for versioning: <tablename> is now a view over <tablename>_ver with INSTEAD OF triggers';
COMMENT ON COLUMN tgsis.versioned_tables.schemaname IS 'schema of the table, its _ver storage and its view';
COMMENT ON COLUMN tgsis.versioned_tables.tablename IS 'original table name, now the name of the view';
COMMENT ON COLUMN tgsis.versioned_tables.shortname IS 'short name used in conflict reports (unique within the object class)';
COMMENT ON COLUMN tgsis.versioned_tables.objectkeyfield IS 'column holding the key of the object a row belongs to';
COMMENT ON COLUMN tgsis.versioned_tables.objectclass IS 'object class: the tables that together store one kind of object';
COMMENT ON COLUMN tgsis.versioned_tables.iudorder IS 'order in which a merge applies the class''s tables (ascending for inserts/updates)';
COMMENT ON COLUMN tgsis.versioned_tables.keycolumns IS 'primary-key columns of the original table (the row key)';
COMMENT ON COLUMN tgsis.versioned_tables.pkeyname IS 'name of the original primary-key constraint (reported by duplicate-key errors, restored on disable)';
COMMENT ON COLUMN tgsis.versioned_tables.tablecomment IS 'the table''s comment before versioning (restored by disable_versioning)';
COMMENT ON COLUMN tgsis.versioned_tables.identity_always IS 'GENERATED ALWAYS identity columns turned BY DEFAULT in _ver (restored on disable)';
COMMENT ON COLUMN tgsis.versioned_tables.enabled_at IS 'when versioning was enabled';
COMMENT ON COLUMN tgsis.versioned_tables.enabled_by IS 'role that enabled it';
