-- tgsis.partition_model_storage(model, partitions): hash-partition the storage tables of a data model by geoid, their rows kept.
-- For a database that will outgrow plain tables (docs/scaling.md): the
-- storage of each table of the model (tgsis.model_tables) is replaced by a
-- table of the same definition (LIKE ... INCLUDING ALL: columns, defaults,
-- checks, keys, indexes and their names, comments, owner, the group roles'
-- rights) partitioned by HASH (geoid) in p_partitions partitions. Every key
-- of the model tables starts with geoid, so the keys (and the (keys...,
-- revision) of versioned storage) contain the partition key. The storage of
-- a row table is the table while plain, <table>_ver once versioned
-- (tgsis.partition_row_storage): its rows, versioned or not, are moved and
-- verified bit for bit, the versioned view made again over it (until this
-- session's change the row path needed the tables empty and unversioned, so
-- a versioned model 1 with data, whose atom and part stay rows beside its
-- chunk tables, was refused). The tables are locked, all checked first
-- (plain storage, keyed by geoid first, used by no view, foreign key,
-- function body or user's trigger — LIKE copies no trigger: refused by name,
-- TG202, as the chunk path refuses one) and then swapped, all in the
-- caller's transaction, so that a refusal changes nothing and no row can be
-- written between the check and the swap. The core tables (model 0:
-- tgsis.geometry and the model sets, with identities and foreign keys) stay
-- plain. The partitions grant nothing of their own, as enable_versioning
-- requires. Run it as the tables' owner (the role that installed tgsis) or
-- a superuser; PUBLIC may not.
-- A table stored in chunks (tgsis.store_in_chunks) has its chunk table
-- tgsis.<table>_chunk partitioned the same way, with its data, versioned or
-- not, its face and chunk view made again (tgsis.partition_chunk_storage, the
-- chunk layer's part: this function lives in the storage layer, below it).
-- Every partition made holds locks until the transaction ends (its table,
-- row type, indexes and their constraints, TOAST table and index), and
-- PostgreSQL's shared lock table is sized for max_locks_per_transaction x
-- (max_connections + max_prepared_transactions) locks of all sessions: a
-- call needing more failed half-way with 53200 out of shared memory (model 1
-- in 512 partitions on a default server). The locks a call needs are
-- estimated from the model's tables before anything is done: per partition
-- of each table 2 + 2 per index + 3 for TOAST, plus 40 per table (30 before the row path moved
-- rows: its copied policies and old table held 21 locks more for model 1 on rows; measured:
-- the estimate is at or above the locks held on PostgreSQL 15 and 18), and a
-- call needing more than that documented size is refused (TG100) with the
-- largest number of partitions the server takes, nothing changed.
CREATE FUNCTION tgsis.partition_model_storage(p_model smallint, p_partitions integer)
RETURNS text[]
LANGUAGE plpgsql
VOLATILE
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_tables  text[];
    v_table   text;
    v_cost    bigint;
    v_fixed   bigint;
    v_room    bigint;
    v_swapped boolean := false;
BEGIN
    PERFORM tgsis.require_storage();  -- a bare CREATE EXTENSION: say what to run (geometry/require_storage.sql)
    IF p_partitions IS NULL OR p_partitions NOT BETWEEN 2 AND 1024 THEN
        RAISE EXCEPTION 'number of partitions % is out of range', coalesce(p_partitions::text, 'NULL')
            USING ERRCODE = 'TG100', HINT = 'give 2 to 1024 partitions';
    END IF;
    IF p_model = 0 THEN
        RAISE EXCEPTION 'the core tables (data model 0) are not partitioned'
            USING ERRCODE = 'TG100',
                  DETAIL = 'tgsis.geometry hands out the geometry ids and is referenced by foreign keys',
                  HINT = 'partition the tables of data models 1 to 5: SELECT model, tablename FROM tgsis.model_tables';
    END IF;
    SELECT array_agg(t.tablename ORDER BY t.tablename) INTO v_tables FROM tgsis.model_tables t WHERE t.model = p_model;
    IF v_tables IS NULL THEN
        RAISE EXCEPTION 'data model % does not exist', coalesce(p_model::text, 'NULL')
            USING ERRCODE = 'TG200', HINT = 'the data models are in tgsis.data_models';
    END IF;

    -- the locks the call will hold at its end, against the lock table's documented size
    SELECT sum(2 + 2 * (SELECT count(*) FROM pg_index i WHERE i.indrelid = c.oid)
               + CASE WHEN c.reltoastrelid <> 0 THEN 3 ELSE 0 END), 40 * count(*)
      INTO v_cost, v_fixed
      FROM unnest(v_tables) AS t(tablename)
      JOIN pg_class c ON c.oid = tgsis.storage_table('tgsis', t.tablename)::regclass;  -- <table>, <table>_ver or _chunk
    v_room := current_setting('max_locks_per_transaction')::bigint
              * (current_setting('max_connections')::bigint + current_setting('max_prepared_transactions')::bigint);
    IF p_partitions * v_cost + v_fixed > v_room THEN
        RAISE EXCEPTION 'data model % in % partitions needs about % locks in one transaction, more than this server''s lock table holds (%)',
                p_model, p_partitions, p_partitions * v_cost + v_fixed, v_room
            USING ERRCODE = 'TG100',
                  DETAIL = format('Each partition of the %s tables of model %s holds %s locks until the transaction ends (its table, row type, indexes, TOAST), %s in all; '
                                  'PostgreSQL''s shared lock table holds max_locks_per_transaction (%s) x (max_connections (%s) + max_prepared_transactions (%s)) = %s locks of all sessions.',
                                  cardinality(v_tables), p_model, v_cost, v_fixed, current_setting('max_locks_per_transaction'),
                                  current_setting('max_connections'), current_setting('max_prepared_transactions'), v_room),
                  HINT = format('give at most %s partitions, or raise max_locks_per_transaction (a server restart) for more',
                                greatest((v_room - v_fixed) / v_cost, 0));
    END IF;

    -- every table first: locked, then checked; nothing is changed before all pass
    FOREACH v_table IN ARRAY v_tables LOOP
        IF tgsis.stored_in_chunks(v_table) THEN  -- locked and checked by the chunk layer: kept with its data
            PERFORM tgsis.partition_chunk_storage(v_table, p_partitions, true);
            CONTINUE;
        END IF;
        -- the row storage (the table, or <table>_ver once versioned): locked and checked, kept with its rows
        PERFORM tgsis.partition_row_storage(v_table, p_partitions, true);
    END LOOP;

    FOREACH v_table IN ARRAY v_tables LOOP
        IF tgsis.stored_in_chunks(v_table) THEN
            PERFORM tgsis.partition_chunk_storage(v_table, p_partitions);  -- its rights made again there
            CONTINUE;
        END IF;
        v_swapped := true;
        PERFORM tgsis.partition_row_storage(v_table, p_partitions);
    END LOOP;
    IF v_swapped THEN  -- the group roles' rights and the policies given again (idempotent)
        PERFORM tgsis.grant_model_tables(p_model);
        PERFORM tgsis.protect_model_tables(p_model);  -- LIKE ... INCLUDING ALL copies no policies
    END IF;
    RETURN v_tables;
END
$$;

REVOKE ALL ON FUNCTION tgsis.partition_model_storage(smallint, integer) FROM PUBLIC;

COMMENT ON FUNCTION tgsis.partition_model_storage(smallint, integer) IS
    'hash-partition the storage tables of a data model (1 to 5) by geoid in 2 to 1024 partitions with their data, versioned or not (row storage: tgsis.partition_row_storage; the chunk tables of tables stored in chunks: tgsis.partition_chunk_storage) (at most what the server''s lock table holds: max_locks_per_transaction x (max_connections + max_prepared_transactions) locks, about 4 per partition of each table; TG100 naming the largest number otherwise), keeping their definitions, index names, comments, owner, rights and per-class row-level security; refused (and nothing changed) when a table is partitioned already or used by other objects; returns the tables';
