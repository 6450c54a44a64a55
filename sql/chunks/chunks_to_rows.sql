-- tgsis.chunks_to_rows(table): write every chunk version of tgsis.<table>_chunk back into the empty row storage as rows, visibility kept.
-- The way back (docs/storage.md, "Upgrading an existing database, and
-- back"), for a downgrade or a tool that needs rows: each present slot of each
-- chunk version becomes a row of the row storage (tgsis.storage_table) with
-- the chunk version's revision and lastrevs, so a row is visible in exactly
-- the sets its chunk version is. Rows a chunk's versions share are repeated
-- per version (more rows than a history of rows would hold; compress_versions
-- does not merge them); rows -> chunks -> rows -> chunks gives the same
-- chunks. Unversioned storage takes every chunk version (it has open ones of
-- revision 0 only; two versions of a key fail its primary key, 23505). Into an EMPTY row storage only (TG201 otherwise: the
-- keys would mix), after locking both tables; verified by
-- tgsis.check_chunk_conversion (TG000: the caller's transaction changes
-- nothing). The row storage's triggers fire as for any insert. Returns the
-- number of rows written. Internal: runs with the caller's rights.
CREATE FUNCTION tgsis.chunks_to_rows(p_table text)
RETURNS bigint
LANGUAGE plpgsql
VOLATILE
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_chunk     regclass;
    v_view      regclass;
    v_storage   regclass;
    v_versioned boolean;
    v_cols      text;
    v_any       boolean;
    v_n         bigint;
BEGIN
    v_chunk := tgsis.chunk_table_of(p_table, true);  -- TG200 / TG100
    v_view := tgsis.chunk_relation(p_table, '_chunk_rows')::regclass;
    v_storage := (SELECT tgsis.storage_table(r.schemaname, r.tablename) FROM tgsis.chunk_registry(p_table) r)::regclass;
    v_versioned := EXISTS (SELECT FROM tgsis.versioned_tables t, tgsis.chunk_registry(p_table) r
                            WHERE t.schemaname = r.schemaname AND t.tablename = r.tablename);
    IF v_versioned THEN
        PERFORM FROM tgsis.versions v ORDER BY v.versionid FOR SHARE;
    END IF;
    EXECUTE format('LOCK TABLE %s IN SHARE MODE', v_chunk);
    EXECUTE format('LOCK TABLE %s IN SHARE ROW EXCLUSIVE MODE', v_storage);
    EXECUTE format('SELECT EXISTS (SELECT FROM %s)', v_storage) INTO STRICT v_any;
    IF v_any THEN
        RAISE EXCEPTION '% holds rows already', v_storage
            USING ERRCODE = 'TG201',
                  DETAIL = format('Chunks are converted into an empty row storage only; %s is not.', v_storage),
                  HINT = 'convert into an empty row storage';
    END IF;
    v_cols := (SELECT string_agg(quote_ident(c.name), ', ' ORDER BY c.colorder) FROM tgsis.chunk_columns(p_table) c);
    IF v_versioned THEN
        EXECUTE format('INSERT INTO %1$s (%2$s, revision, lastrevs) SELECT %2$s, revision, lastrevs FROM %3$s',
                       v_storage, v_cols, v_view);
    ELSE
        EXECUTE format('INSERT INTO %1$s (%2$s) SELECT %2$s FROM %3$s',
                       v_storage, v_cols, v_view);
    END IF;
    GET DIAGNOSTICS v_n = ROW_COUNT;
    PERFORM tgsis.check_chunk_conversion(p_table);
    RETURN v_n;
END
$$;

REVOKE ALL ON FUNCTION tgsis.chunks_to_rows(text) FROM PUBLIC;

COMMENT ON FUNCTION tgsis.chunks_to_rows(text) IS
    'write every chunk version of tgsis.<table>_chunk into the empty row storage (TG201 otherwise): one row per present slot with the chunk version''s revision and lastrevs (unversioned: every chunk version, its key once), so visibility is kept exactly; verified by tgsis.check_chunk_conversion (TG000); returns the rows written';
