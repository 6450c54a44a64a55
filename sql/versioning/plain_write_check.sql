-- tgsis.plain_write_check(schema, table): refuse (TG305) a write to a table that is not versioned while the session is not in DEFAULT's working revision.
-- A plain table holds one state, the one every version reads: a write made
-- "in" version v1 (goto_version, SET tgsis.version) would silently land in
-- DEFAULT. The write functions of features (new_geometry, delete_geometry,
-- refresh_geometry, add_instant, delete_instant) call this first; the views of
-- versioned tables need no such check. Reads only settings and the registry.
CREATE FUNCTION tgsis.plain_write_check(p_schema text, p_table text)
RETURNS void
LANGUAGE plpgsql
STABLE
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_version text := tgsis.get_working_version();
    v_viewing integer := tgsis.get_viewing_revision();
    v_working integer;
BEGIN
    IF EXISTS (SELECT FROM tgsis.versioned_tables t WHERE t.schemaname = p_schema AND t.tablename = p_table) THEN
        RETURN;
    END IF;
    SELECT v.workingrevision INTO v_working FROM tgsis.versions v WHERE v.name = v_version;
    IF v_version = 'DEFAULT' AND (v_viewing IS NULL OR v_viewing = v_working) THEN
        RETURN;
    END IF;
    IF v_version <> 'DEFAULT' THEN
        RAISE EXCEPTION 'table %.% is not versioned: a write in version % would change DEFAULT, which every version reads',
                        p_schema, p_table, quote_literal(v_version)
            USING ERRCODE = 'TG305',
                  DETAIL = format('The session works in version %L (setting tgsis.version), but feature versioning is off, '
                                  'so the table holds one state for all versions. Nothing was written.', v_version),
                  HINT = 'SELECT tgsis.enable_feature_versioning() to write features in versions, '
                         'or SELECT tgsis.goto_version(''DEFAULT'') to write in DEFAULT';
    END IF;
    RAISE EXCEPTION 'table %.% is not versioned: DEFAULT viewed at revision % cannot be written', p_schema, p_table, v_viewing
        USING ERRCODE = 'TG305',
              DETAIL = 'The session looks at an older revision (setting tgsis.revision); the table holds only the current state. Nothing was written.',
              HINT = 'SELECT tgsis.goto_version(''DEFAULT'') to write the current state';
END
$$;

COMMENT ON FUNCTION tgsis.plain_write_check(text, text) IS
    'refuse (TG305) a write to a table that is not versioned while the session works in a version other than DEFAULT or views an older revision: the write would land in DEFAULT; no-op for versioned tables';
