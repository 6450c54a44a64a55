-- Which tgsis versions were installed in this database, and how. The plain-SQL
-- route (tgsis.install) reads the newest row to decide between a no-op and an
-- upgrade; the extension route has pg_extension for that and writes here too.
CREATE TABLE tgsis.installation (
    version      text        PRIMARY KEY,
    method       text        NOT NULL CHECK (method IN ('extension', 'sql')),
    installed_at timestamptz NOT NULL DEFAULT now(),
    installed_by name        NOT NULL DEFAULT current_user,
    fingerprint  text
);

COMMENT ON TABLE tgsis.installation IS
    'history of the tgsis versions installed or upgraded to in this database (newest installed_at is current)';
COMMENT ON COLUMN tgsis.installation.version IS 'tgsis version whose script ran';
COMMENT ON COLUMN tgsis.installation.method IS
    'extension: CREATE/ALTER EXTENSION; sql: the same script run by tgsis.install() where extension files cannot be installed';
COMMENT ON COLUMN tgsis.installation.installed_at IS 'when the script ran (transaction start)';
COMMENT ON COLUMN tgsis.installation.installed_by IS 'role that ran it';
COMMENT ON COLUMN tgsis.installation.fingerprint IS
    'sha256 (first 16 hex digits) of the install script of that version as built (tgsis.install and tgsis db status compare it with the client''s); NULL for versions before 0.3.0';

-- While CREATE EXTENSION runs its script, pg_extension already has the row.
-- The fingerprint is put in by the build (sql/Makefile, tgsis.db.sqlsource) with the sha256 of
-- the install script it is part of: within a development version the SQL changes from commit to
-- commit, and the version alone cannot tell two builds apart.
INSERT INTO tgsis.installation (version, method, fingerprint)
VALUES ('@TGSIS_VERSION@',
        CASE WHEN EXISTS (SELECT FROM pg_catalog.pg_extension WHERE extname = 'tgsis')
             THEN 'extension' ELSE 'sql' END,
        '@TGSIS_FINGERPRINT@');
