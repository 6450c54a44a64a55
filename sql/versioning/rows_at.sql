-- tgsis.rows_at(NULL::table, version, revision): the rows of a versioned table as a version (at a revision) sees them.
-- Does not change the session's version. Usage:
--   SELECT * FROM tgsis.rows_at(NULL::public.wells, 'v1');
--   SELECT * FROM tgsis.rows_at(NULL::public.wells, 'DEFAULT', 12);
CREATE FUNCTION tgsis.rows_at(p_table anyelement, p_version text, p_revision integer DEFAULT NULL)
RETURNS SETOF anyelement
LANGUAGE plpgsql
STABLE
AS $$
DECLARE
    v_t    tgsis.versioned_tables;
    v_rel  oid := (SELECT typrelid FROM pg_catalog.pg_type WHERE oid = pg_typeof(p_table));
    v_set  integer[];
    v_cols text;
BEGIN
    IF v_rel = 0 THEN
        RAISE EXCEPTION 'rows_at takes a row of the versioned table, not a %', pg_typeof(p_table)
            USING ERRCODE = 'TG100', HINT = 'call it as tgsis.rows_at(NULL::schema.table, version[, revision])';
    END IF;
    v_t := tgsis.versioned_table(v_rel::regclass);  -- TG200 unless it is a versioned table's view
    v_set := tgsis.revision_set(tgsis.version_id(p_version), p_revision);
    SELECT string_agg(format('v.%I', attname), ', ' ORDER BY attnum) INTO v_cols
      FROM pg_catalog.pg_attribute WHERE attrelid = v_rel AND attnum > 0 AND NOT attisdropped;
    -- (the stored row versions: <table>_ver, or a chunked model table's decoded chunk versions)
    RETURN QUERY EXECUTE format('SELECT %s FROM %s v WHERE %s',
                                v_cols, tgsis.storage_rows(v_t), tgsis.visible_versions('v', '$1'))
                 USING v_set;
END
$$;

COMMENT ON FUNCTION tgsis.rows_at(anyelement, text, integer) IS
    'rows of a versioned table as version p_version sees them (at p_revision, default its working revision), without changing the session: tgsis.rows_at(NULL::schema.table, ''v1'')';
