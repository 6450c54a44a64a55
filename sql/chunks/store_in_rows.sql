-- tgsis.store_in_rows(table): store a model table as rows again, after tgsis.store_in_chunks: the way back of the storage switch.
-- docs/storage.md, "The storage switch" and "Upgrading an existing database,
-- and back". In one transaction: the face tgsis.<table> is set aside, the
-- row table is made again from the row definition the switch kept
-- (tgsis.<table>_shape: columns, NOT NULLs, CHECKs, key, comments) with the
-- face's grants, its row-level security made as a fresh install makes it
-- (tgsis.protect_model_tables); a versioned table is versioned again by
-- tgsis.enable_versioning_rel (its <table>_ver, versioned view, queue, write
-- function and runner as tgsis.enable_feature_versioning makes them; the
-- registration's other fields -- when and by whom versioning was enabled, the
-- table's comment -- kept); every chunk version is written back as rows with
-- its revision and lastrevs and verified against every version's and
-- revision's set (tgsis.chunks_to_rows, TG000: nothing changed); then the
-- face, the decoded view, the chunk table and the shape go, and the
-- conflicts' marks are renewed (solved conflicts stay solved), as
-- tgsis.store_in_chunks does the other way. Row versions a chunk's versions
-- share are repeated per version: what every set sees is kept, not the count
-- of row versions. Refused by name: a table not stored in chunks (TG200),
-- chunk storage partitioned by tgsis.partition_model_storage (TG100: the
-- rows would not be partitioned alike); a user's view over the face blocks
-- it (PostgreSQL's 2BP01 names the view; nothing changed). Internal
-- (tgsis's owner, as tgsis.store_in_chunks: it creates and drops the
-- storage). Returns the rows written.
CREATE FUNCTION tgsis.store_in_rows(p_table text)
RETURNS bigint
LANGUAGE plpgsql
VOLATILE
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_reg       tgsis.model_tables;
    v_face      regclass;
    v_shape     regclass;
    v_chunk     regclass;
    v_c         record;
    v_n         bigint;
    v_comment   text;
    v_versioned tgsis.versioned_tables;
    v_marks     jsonb;
BEGIN
    SELECT * INTO v_reg FROM tgsis.model_tables t WHERE t.tablename = p_table;
    IF NOT FOUND OR NOT tgsis.stored_in_chunks(p_table) THEN
        RAISE EXCEPTION 'tgsis.% is not stored in chunks', coalesce(quote_ident(p_table), 'NULL')
            USING ERRCODE = 'TG200', DETAIL = 'Only what tgsis.store_in_chunks stored goes back to rows.',
                  HINT = 'SELECT tablename FROM tgsis.model_tables WHERE tgsis.stored_in_chunks(tablename) lists them';
    END IF;
    -- refused while another session's snapshot predates this transaction: it would read the row table EMPTY
    PERFORM tgsis.older_snapshots_check(format('tgsis.store_in_rows(%L)', p_table));
    v_face := format('tgsis.%I', p_table)::regclass;
    v_shape := format('tgsis.%I', p_table || '_shape')::regclass;
    v_chunk := format('tgsis.%I', p_table || '_chunk')::regclass;
    IF (SELECT c.relkind FROM pg_class c WHERE c.oid = v_chunk) = 'p' THEN
        RAISE EXCEPTION '% is partitioned: its rows would not be', v_chunk
            USING ERRCODE = 'TG100',
                  DETAIL = 'tgsis.store_in_rows makes one row table; the chunk storage is hash-partitioned (tgsis.partition_model_storage).',
                  HINT = 'keep this table stored in chunks';
    END IF;
    -- a DBA's index on the chunk table would go with it: refused by name (TG202), nothing changed
    PERFORM tgsis.unkept_indexes_check(v_chunk, true, format('tgsis.store_in_rows(%L)', p_table));
    SELECT * INTO v_versioned FROM tgsis.versioned_tables t WHERE t.schemaname = 'tgsis' AND t.tablename = p_table;
    IF v_versioned.tablename IS NOT NULL THEN
        -- the versions' sets stay as they are until the switch is done (as tgsis.chunks_to_rows holds them); the
        -- conflicts' marks fingerprint the stored versions: read before, renewed after (tgsis.renew_conflict_marks)
        PERFORM FROM tgsis.versions v ORDER BY v.versionid FOR SHARE;
        v_marks := tgsis.conflict_marks();
    END IF;
    EXECUTE format('LOCK TABLE %s IN SHARE ROW EXCLUSIVE MODE', v_chunk);
    -- the table's own comment: the registration's (versioned), else the face's first part (tgsis.create_chunk_face)
    v_comment := coalesce(v_versioned.tablecomment, split_part(obj_description(v_face, 'pg_class'), ', stored in chunks (', 1));
    EXECUTE format('ALTER VIEW %s RENAME TO %I', v_face, p_table || '_face');
    EXECUTE format('CREATE TABLE tgsis.%I (LIKE %s INCLUDING CONSTRAINTS INCLUDING COMMENTS)', p_table, v_shape);
    EXECUTE format('ALTER TABLE tgsis.%I DROP CONSTRAINT %I', p_table, p_table || '_shape_holds_no_rows');
    FOR v_c IN SELECT pg_get_constraintdef(con.oid) AS def FROM pg_constraint con
                WHERE con.conrelid = v_shape AND con.contype = 'p' LOOP
        EXECUTE format('ALTER TABLE tgsis.%I ADD CONSTRAINT %I %s', p_table,
                       coalesce(v_versioned.pkeyname, p_table || '_pkey'), v_c.def);
    END LOOP;
    PERFORM tgsis.move_row_indexes(v_shape, format('tgsis.%I', p_table)::regclass);  -- the row table's own indexes, by name
    EXECUTE format('COMMENT ON TABLE tgsis.%I IS %L', p_table, v_comment);
    PERFORM tgsis.copy_relation_rights(v_face, format('tgsis.%I', p_table)::regclass);  -- the face's grants, grant options kept
    -- the shape is the marker of chunk storage (tgsis.stored_in_chunks): once it goes, tgsis.storage_table names the rows
    EXECUTE format('DROP TABLE %s', v_shape);
    IF v_versioned.tablename IS NOT NULL THEN
        -- versioned again as tgsis.enable_feature_versioning versions a model table, the registration kept
        DELETE FROM tgsis.versioned_tables t WHERE t.schemaname = 'tgsis' AND t.tablename = p_table;
        PERFORM tgsis.enable_versioning_rel(format('tgsis.%I', p_table)::regclass, v_versioned.objectkeyfield,
                                            v_versioned.objectclass, v_versioned.iudorder, v_versioned.shortname);
        UPDATE tgsis.versioned_tables t
           SET tablecomment = v_versioned.tablecomment, identity_always = v_versioned.identity_always,
               enabled_at = v_versioned.enabled_at, enabled_by = v_versioned.enabled_by
         WHERE t.schemaname = 'tgsis' AND t.tablename = p_table;
    END IF;
    PERFORM tgsis.protect_model_tables(v_reg.model);  -- the per-class row-level security of the row storage
    v_n := tgsis.chunks_to_rows(p_table);  -- verified (TG000: nothing changed)
    -- this transaction's tables of rows written through the face (tgsis.chunk_face_write) are of its row type; another
    -- session's exist only while its writing transaction is open (ON COMMIT DROP), and would block the DROP below by
    -- name (2BP01: nothing changed); a session idle after it wrote holds none
    EXECUTE format('DROP TABLE IF EXISTS %s, %s, %s, %s', tgsis.chunk_face_work(p_table, 'now'),
                   tgsis.chunk_face_work(p_table, 'queue'), tgsis.chunk_face_work(p_table, 'rows'), tgsis.chunk_face_work(p_table, 'dels'));
    EXECUTE format('DROP VIEW %s', v_face);
    IF p_table = 'd4dvrtx' THEN
        DROP VIEW IF EXISTS tgsis.d4dvrtx_arrays;  -- model 3's arrays for tgsis.vertices_at (tgsis.create_chunk_face)
    END IF;
    EXECUTE format('DROP FUNCTION IF EXISTS %I.%I()', 'tgsis', p_table || '_face_row');  -- its row function (tgsis.create_chunk_face)
    EXECUTE format('DROP VIEW %s', tgsis.chunk_relation(p_table, '_chunk_rows'));
    EXECUTE format('DROP TABLE %s', v_chunk);
    EXECUTE format('ANALYZE %s', tgsis.storage_table('tgsis', p_table));
    IF v_versioned.tablename IS NOT NULL THEN
        PERFORM tgsis.renew_conflict_marks(v_marks);
    END IF;
    -- again last, and at COMMIT: a snapshot taken while the switch ran, or before its transaction commits, would
    -- read the new row table EMPTY as well
    PERFORM tgsis.older_snapshots_check(format('tgsis.store_in_rows(%L)', p_table));
    PERFORM tgsis.older_snapshots_at_commit(format('tgsis.store_in_rows(%L)', p_table));
    RETURN v_n;
END
$$;

REVOKE ALL ON FUNCTION tgsis.store_in_rows(text) FROM PUBLIC;

COMMENT ON FUNCTION tgsis.store_in_rows(text) IS
    'store a model table as rows again after tgsis.store_in_chunks: the row table made from its kept definition with the face''s grants and the model''s row-level security, versioned again when it was (tgsis.enable_versioning_rel, its registration kept), filled from every chunk version and verified (tgsis.chunks_to_rows, TG000), the face, decoded view, chunk table and shape dropped, the conflicts'' marks renewed; TG200 when not stored in chunks, TG100 for partitioned chunk storage; returns the rows written';
