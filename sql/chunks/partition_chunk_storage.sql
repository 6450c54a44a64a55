-- tgsis.partition_chunk_storage(table, partitions, check_only): hash-partition the chunk table of a model table stored in chunks by geoid.
-- The chunk part of tgsis.partition_model_storage (docs/scaling.md,
-- docs/storage.md "partition_model_storage and Citus"): tgsis.<table>_chunk
-- is replaced by a table of the same definition (LIKE ... INCLUDING ALL:
-- columns, compression, generated revclosed, keys and revision indexes with
-- their names, comments) partitioned by HASH (geoid) in p_partitions
-- partitions <table>_chunk_p<r>, the partition scheme of row storage, so an
-- object's chunks and its rows of other tables share a remainder. Unlike row
-- storage it need not be empty nor unversioned: a chunk is one row per ~1,000
-- ids, so its chunk versions are copied (and verified: the new table holds
-- exactly the old one's rows, every column compared by its send form, so every
-- version and revision sees the same chunks, bit for bit; TG000 and nothing
-- changed otherwise). The face tgsis.<table> and the decoded
-- tgsis.<table>_chunk_rows stay the same views (CREATE OR REPLACE VIEW with
-- their own definitions, now read from the new table: their oids, grants,
-- comments, triggers, the users' views over them and the sessions' work tables
-- of the face's writer, typed by the face's row, are kept); the chunk table
-- gets the old one's owner, grants, row-level security and policies, and the
-- guards of versioned storage again (tgsis.guard_chunk_storage). Refused
-- (TG202, nothing changed): a chunk table partitioned already, or one other
-- objects use directly (views, functions, foreign keys, the users' triggers,
-- which would be lost), the temporary name taken. p_check_only: lock and
-- check only (tgsis.partition_model_storage checks every table of a model
-- before changing any). The caller checks the lock estimate. Internal:
-- tgsis's owner, who owns the storage; in the caller's transaction. Returns
-- the chunk versions moved.
CREATE FUNCTION tgsis.partition_chunk_storage(p_table text, p_partitions integer, p_check_only boolean DEFAULT false)
RETURNS bigint
LANGUAGE plpgsql
VOLATILE
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_name      text := p_table || '_chunk';
    v_old       text := 'tgsis_old_' || p_table || '_chunk';
    v_chunk     regclass;
    v_face      regclass;
    v_keep      regclass[];  -- the views over the chunk table made again over the partitioned one
    v_view      regclass;
    v_kind      "char";
    v_users     text;
    v_n         bigint;
    v_new       regclass;
BEGIN
    IF NOT tgsis.stored_in_chunks(p_table) THEN
        RAISE EXCEPTION 'tgsis.% is not stored in chunks', quote_ident(p_table)
            USING ERRCODE = 'TG200', HINT = 'partition the model tables with tgsis.partition_model_storage';
    END IF;
    IF p_partitions IS NULL OR p_partitions NOT BETWEEN 2 AND 1024 THEN
        RAISE EXCEPTION 'number of partitions % is out of range', coalesce(p_partitions::text, 'NULL')
            USING ERRCODE = 'TG100', HINT = 'give 2 to 1024 partitions';
    END IF;
    -- the writers' order: the face, then the chunk table (the face's triggers write it)
    EXECUTE format('LOCK TABLE tgsis.%I, tgsis.%I, tgsis.%I IN ACCESS EXCLUSIVE MODE', p_table, p_table || '_chunk_rows', v_name);
    v_chunk := format('tgsis.%I', v_name)::regclass;
    v_face := format('tgsis.%I', p_table)::regclass;
    v_view := format('tgsis.%I', p_table || '_chunk_rows')::regclass;
    SELECT c.relkind INTO v_kind FROM pg_class c WHERE c.oid = v_chunk;
    IF v_kind <> 'r' THEN
        RAISE EXCEPTION 'tgsis.% is not a plain table', quote_ident(p_table)
            USING ERRCODE = 'TG202',
                  DETAIL = format('It is stored in chunks, and its chunk table tgsis.%I is %s.', v_name,
                                  CASE v_kind WHEN 'p' THEN 'partitioned already' ELSE 'no table' END),
                  HINT = 'partition the model tables once';
    END IF;
    -- what refers to the chunk table, besides the face and the chunk view (made again over the new one), would
    -- block the swap or be lost; the guards of versioned storage and the insert check are made again
    -- (and model 3's arrays for tgsis.vertices_at, tgsis.d4dvrtx_arrays: made again over the new one too)
    v_keep := ARRAY[v_face, v_view] || ARRAY(SELECT to_regclass('tgsis.d4dvrtx_arrays') WHERE p_table = 'd4dvrtx'
                                                AND to_regclass('tgsis.d4dvrtx_arrays') IS NOT NULL);
    v_users := tgsis.relation_users(v_chunk, v_keep,
                                    ARRAY['tgsis_storage_write', 'tgsis_storage_rows', 'tgsis_storage_changes', 'tgsis_chunk_insert']::name[]);
    IF v_users IS NOT NULL THEN
        RAISE EXCEPTION 'tgsis.% is used by other objects', quote_ident(p_table)
            USING ERRCODE = 'TG202', DETAIL = 'used by: ' || v_users,
                  HINT = 'drop them, partition the model tables, then create them again';
    END IF;
    IF to_regclass(format('tgsis.%I', v_old)) IS NOT NULL THEN
        RAISE EXCEPTION 'tgsis.% exists already', quote_ident(v_old)
            USING ERRCODE = 'TG202', DETAIL = 'Partitioning a chunk table needs this name for the old chunk table.',
                  HINT = 'drop or rename them, then partition the model tables';
    END IF;
    IF p_check_only THEN
        RETURN 0;
    END IF;

    -- the partitioned chunk table in its place, its chunk versions moved and verified, the face and the chunk view
    -- reading it
    v_n := tgsis.swap_into_hash_partitions(v_chunk, p_partitions, v_keep);
    v_new := format('tgsis.%I', v_name)::regclass;
    PERFORM tgsis.create_chunk_insert_trigger(p_table, v_new);  -- direct inserts checked as before
    IF EXISTS (SELECT FROM tgsis.versioned_tables t WHERE t.schemaname = 'tgsis' AND t.tablename = p_table) THEN
        PERFORM tgsis.guard_chunk_storage(p_table);  -- the rights, labels and notes its triggers kept
    END IF;
    RETURN v_n;
END
$$;

REVOKE ALL ON FUNCTION tgsis.partition_chunk_storage(text, integer, boolean) FROM PUBLIC;

COMMENT ON FUNCTION tgsis.partition_chunk_storage(text, integer, boolean) IS
    'hash-partition tgsis.<table>_chunk of a model table stored in chunks by geoid in 2 to 1024 partitions <table>_chunk_p<r> (the scheme of tgsis.partition_model_storage, which calls it), its chunk versions moved and verified bit for bit (TG000 on a difference), the face tgsis.<table> and tgsis.<table>_chunk_rows kept (the same views, reading the new table), the rights, row-level security and the guards of versioned storage made again as they were; TG202 when partitioned already or when other objects use the chunk table; p_check_only: lock and check only; returns the chunk versions moved';
