-- tgsis.partition_row_storage(table, partitions, check_only): hash-partition the row storage of a model table by geoid, its rows kept and verified.
-- The row tables' part of tgsis.partition_model_storage (the chunk tables'
-- is tgsis.partition_chunk_storage): the storage of tgsis.<table> — the table
-- itself while plain, tgsis.<table>_ver once versioned (tgsis.<table> is then
-- its versioned view) — is replaced by a table of the same definition (LIKE
-- ... INCLUDING ALL: columns, defaults, checks, keys, indexes under their
-- names, comment, owner) partitioned by HASH (geoid) in p_partitions
-- partitions (tgsis.create_hash_partitions). Its rows, versioned or not, are
-- copied and verified (the new table holds exactly the old one's rows, every
-- column compared by its send form, doubles bit for bit, so every version
-- and revision sees the same rows; TG000 and nothing changed otherwise), so
-- that model 1 with data, whose atom and part stay rows beside its chunk
-- tables, is partitioned as its chunks are. The new table gets the old one's
-- grants, row-level security and policies (tgsis.copy_relation_rights),
-- tgsis's triggers of versioned storage again (their definitions, read
-- before the swap), and the versioned view reads it (CREATE OR REPLACE VIEW
-- with its own definition: its oid, grants, comment, triggers and the users'
-- views over it are kept). Refused (TG202, nothing changed): storage that is
-- no plain table (partitioned already, missing), not keyed by geoid first,
-- or used by other objects (views, foreign keys, function bodies, a user's
-- trigger, which LIKE would not copy: named), the temporary name taken.
-- p_check_only: lock and check only (tgsis.partition_model_storage checks
-- every table of a model before changing any). The caller checks the lock
-- estimate and gives the model's rights again afterwards. Internal: tgsis's
-- owner, who owns the storage; in the caller's transaction. Returns the rows
-- moved.
CREATE FUNCTION tgsis.partition_row_storage(p_table text, p_partitions integer, p_check_only boolean DEFAULT false)
RETURNS bigint
LANGUAGE plpgsql
VOLATILE
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_versioned boolean;
    v_name      text;
    v_old       text;
    v_store     regclass;
    v_face      regclass;
    v_kind      "char";
    v_users     text;
    v_triggers  text[];
    v_trigger   text;
    v_n         bigint;
BEGIN
    IF p_partitions IS NULL OR p_partitions NOT BETWEEN 2 AND 1024 THEN
        RAISE EXCEPTION 'number of partitions % is out of range', coalesce(p_partitions::text, 'NULL')
            USING ERRCODE = 'TG100', HINT = 'give 2 to 1024 partitions';
    END IF;
    v_versioned := EXISTS (SELECT FROM tgsis.versioned_tables t WHERE t.schemaname = 'tgsis' AND t.tablename = p_table);
    v_name := CASE WHEN v_versioned THEN p_table || '_ver' ELSE p_table END;
    v_old := 'tgsis_old_' || v_name;
    -- first the locks, the writers' order (the view, then its storage): they wait for writers, and for a
    -- concurrent call, whose tables the names then give
    IF to_regclass(format('tgsis.%I', p_table)) IS NOT NULL THEN
        EXECUTE format('LOCK TABLE tgsis.%I IN ACCESS EXCLUSIVE MODE', p_table);
    END IF;
    IF v_versioned AND to_regclass(format('tgsis.%I', v_name)) IS NOT NULL THEN
        EXECUTE format('LOCK TABLE tgsis.%I IN ACCESS EXCLUSIVE MODE', v_name);
    END IF;
    v_store := to_regclass(format('tgsis.%I', v_name));
    v_face := CASE WHEN v_versioned THEN to_regclass(format('tgsis.%I', p_table)) END;
    SELECT c.relkind INTO v_kind FROM pg_class c WHERE c.oid = v_store;
    IF v_store IS NULL OR v_kind <> 'r' THEN
        RAISE EXCEPTION 'tgsis.% is not a plain table', quote_ident(v_name)
            USING ERRCODE = 'TG202',
                  DETAIL = CASE v_kind WHEN 'p' THEN 'it is partitioned already' ELSE 'it is missing' END,
                  HINT = 'partition the model tables once';
    END IF;
    -- what refers to the storage, besides its versioned view (made again over the new one), would block the
    -- swap; a user's trigger would be lost (LIKE copies none; tgsis's own, of versioned storage, are made again)
    v_users := tgsis.relation_users(v_store, CASE WHEN v_face IS NOT NULL THEN ARRAY[v_face] ELSE '{}' END,
                                    CASE WHEN v_versioned
                                         THEN ARRAY['tgsis_storage_write', 'tgsis_storage_rows', 'tgsis_storage_changes']::name[]
                                         ELSE '{}' END);
    IF v_users IS NOT NULL THEN
        RAISE EXCEPTION 'tgsis.% is used by other objects', quote_ident(v_name)
            USING ERRCODE = 'TG202', DETAIL = 'used by: ' || v_users,
                  HINT = 'drop them, partition the model tables, then create them again';
    END IF;
    IF NOT EXISTS (SELECT FROM pg_constraint k JOIN pg_attribute a ON a.attrelid = k.conrelid AND a.attnum = k.conkey[1]
                    WHERE k.conrelid = v_store AND k.contype = 'p' AND a.attname = 'geoid') THEN
        RAISE EXCEPTION 'tgsis.% is not keyed by geoid first', quote_ident(v_name)
            USING ERRCODE = 'TG202', HINT = 'only tables whose primary key starts with geoid can be partitioned by it';
    END IF;
    IF to_regclass(format('tgsis.%I', v_old)) IS NOT NULL THEN
        RAISE EXCEPTION 'tgsis.% exists already', quote_ident(v_old)
            USING ERRCODE = 'TG202', DETAIL = 'Partitioning a model table needs this name for its old storage.',
                  HINT = 'drop or rename it, then partition the model tables';
    END IF;
    IF p_check_only THEN
        RETURN 0;
    END IF;

    -- tgsis's triggers of versioned storage, read while they name the old table tgsis.<name> (the same text
    -- names the new one), made again once the rows are moved (nothing to note)
    SELECT array_agg(pg_get_triggerdef(t.oid) ORDER BY t.tgname) INTO v_triggers
      FROM pg_trigger t WHERE NOT t.tgisinternal AND t.tgrelid = v_store;
    v_n := tgsis.swap_into_hash_partitions(v_store, p_partitions,
                                           CASE WHEN v_face IS NOT NULL THEN ARRAY[v_face] ELSE '{}' END);
    FOREACH v_trigger IN ARRAY coalesce(v_triggers, '{}') LOOP
        EXECUTE v_trigger;
    END LOOP;
    RETURN v_n;
END
$$;

REVOKE ALL ON FUNCTION tgsis.partition_row_storage(text, integer, boolean) FROM PUBLIC;

COMMENT ON FUNCTION tgsis.partition_row_storage(text, integer, boolean) IS
    'hash-partition the row storage of model table tgsis.<table> (the table, or tgsis.<table>_ver when versioned) by geoid in 2 to 1024 partitions (the scheme of tgsis.partition_model_storage, which calls it), its rows moved and verified bit for bit (TG000 on a difference), the versioned view kept (reading the new table), the rights, row-level security and tgsis''s triggers of versioned storage made again as they were; TG202 when no plain table, not keyed by geoid first, or used by other objects (a user''s trigger included); p_check_only: lock and check only; returns the rows moved';
