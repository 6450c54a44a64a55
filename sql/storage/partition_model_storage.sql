-- tgsis.partition_model_storage(model, partitions): hash-partition the empty storage tables of a data model by geoid.
-- For a database that will outgrow plain tables (docs/scaling.md): each
-- table of the model (tgsis.model_tables) is replaced by a table of the
-- same definition (LIKE ... INCLUDING ALL: columns, defaults, checks, keys,
-- indexes and their names, comments, owner, the group roles' rights)
-- partitioned by HASH (geoid) in p_partitions partitions. Every key of the
-- model tables starts with geoid, so the keys (and the (keys..., revision)
-- of versioned storage) contain the partition key. Only before data is
-- stored and before feature versioning: the tables are locked, checked to
-- be plain, empty, keyed by geoid first and used by no view, foreign key or
-- function body, and then swapped, all in the
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
-- of each table 2 + 2 per index + 3 for TOAST, plus 30 per table (measured:
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
    v_rel     regclass;
    v_kind    "char";
    v_owner   name;
    v_comment text;
    v_users   text;
    v_index   record;
    v_names   text[];
    v_defs    text[];
    v_rows    boolean;
    v_new     regclass;
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
               + CASE WHEN c.reltoastrelid <> 0 THEN 3 ELSE 0 END), 30 * count(*)
      INTO v_cost, v_fixed
      FROM unnest(v_tables) AS t(tablename)
      JOIN pg_class c ON c.oid = to_regclass(format('tgsis.%I', t.tablename || CASE WHEN tgsis.stored_in_chunks(t.tablename)
                                                                                     THEN '_chunk' ELSE '' END));
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
        IF to_regclass(format('tgsis.%I', v_table)) IS NOT NULL THEN
            -- first the lock (it waits for writers, and for a concurrent call, whose tables the name then gives)
            EXECUTE format('LOCK TABLE tgsis.%I IN ACCESS EXCLUSIVE MODE', v_table);
        END IF;
        v_rel := to_regclass(format('tgsis.%I', v_table));
        SELECT c.relkind INTO v_kind FROM pg_class c WHERE c.oid = v_rel;
        IF v_rel IS NULL OR v_kind <> 'r' THEN
            RAISE EXCEPTION 'tgsis.% is not a plain table', v_table
                USING ERRCODE = 'TG202',
                      DETAIL = CASE v_kind WHEN 'p' THEN 'it is partitioned already'
                                           WHEN 'v' THEN 'feature versioning made it a view of tgsis.' || v_table || '_ver'
                                           ELSE 'it is missing' END,
                      HINT = 'partition the model tables once, before storing data and before tgsis.enable_feature_versioning()';
        END IF;
        -- what refers to the table (views, foreign keys, SQL-standard function bodies) would block the swap
        SELECT string_agg(DISTINCT CASE WHEN d.classid = 'pg_rewrite'::regclass
                                        THEN (SELECT 'view ' || r.ev_class::regclass::text FROM pg_rewrite r WHERE r.oid = d.objid)
                                        ELSE pg_describe_object(d.classid, d.objid, 0) END, ', ') INTO v_users
          FROM pg_depend d
         WHERE d.refclassid = 'pg_class'::regclass AND d.refobjid = v_rel AND d.deptype = 'n'
           AND NOT (d.classid = 'pg_constraint'::regclass        -- the table's own checks name its columns
                    AND EXISTS (SELECT FROM pg_constraint c WHERE c.oid = d.objid AND c.conrelid = v_rel))
           AND NOT (d.classid = 'pg_trigger'::regclass
                    AND EXISTS (SELECT FROM pg_trigger t WHERE t.oid = d.objid AND t.tgrelid = v_rel))
           AND NOT (d.classid = 'pg_policy'::regclass            -- its own policies (made again after the swap)
                    AND EXISTS (SELECT FROM pg_policy p WHERE p.oid = d.objid AND p.polrelid = v_rel))
           AND d.classid <> 'pg_attrdef'::regclass;
        IF v_users IS NOT NULL THEN
            RAISE EXCEPTION 'tgsis.% is used by other objects', v_table
                USING ERRCODE = 'TG202', DETAIL = 'used by: ' || v_users,
                      HINT = 'drop them, partition the model tables, then create them again';
        END IF;
        IF NOT EXISTS (SELECT FROM pg_constraint k JOIN pg_attribute a ON a.attrelid = k.conrelid AND a.attnum = k.conkey[1]
                        WHERE k.conrelid = v_rel AND k.contype = 'p' AND a.attname = 'geoid') THEN
            RAISE EXCEPTION 'tgsis.% is not keyed by geoid first', v_table
                USING ERRCODE = 'TG202', HINT = 'only tables whose primary key starts with geoid can be partitioned by it';
        END IF;
        EXECUTE format('SELECT EXISTS (SELECT FROM tgsis.%I)', v_table) INTO STRICT v_rows;
        IF v_rows THEN
            RAISE EXCEPTION 'tgsis.% holds rows', v_table
                USING ERRCODE = 'TG202',
                      DETAIL = 'its rows would have to be moved; partitioning is for storage that is still empty',
                      HINT = 'partition the model tables before storing data (a dump restored into a partitioned database keeps its rows)';
        END IF;
    END LOOP;

    FOREACH v_table IN ARRAY v_tables LOOP
        IF tgsis.stored_in_chunks(v_table) THEN
            PERFORM tgsis.partition_chunk_storage(v_table, p_partitions);  -- its rights made again there
            CONTINUE;
        END IF;
        v_swapped := true;
        v_rel := format('tgsis.%I', v_table)::regclass;
        SELECT c.relowner::regrole::name, obj_description(c.oid, 'pg_class') INTO v_owner, v_comment
          FROM pg_class c WHERE c.oid = v_rel;
        -- the indexes' names, by what each indexes (the text after USING), for the new table's indexes to take
        SELECT array_agg(c.relname::text ORDER BY c.relname), array_agg(split_part(pg_get_indexdef(i.indexrelid), ' USING ', 2) ORDER BY c.relname)
          INTO v_names, v_defs
          FROM pg_index i JOIN pg_class c ON c.oid = i.indexrelid WHERE i.indrelid = v_rel;
        EXECUTE format('ALTER TABLE tgsis.%I RENAME TO %I', v_table, 'tgsis_old_' || v_table);
        EXECUTE format('CREATE TABLE tgsis.%I (LIKE tgsis.%I INCLUDING ALL) PARTITION BY HASH (geoid)',
                       v_table, 'tgsis_old_' || v_table);
        EXECUTE format('DROP TABLE tgsis.%I', 'tgsis_old_' || v_table);
        v_new := format('tgsis.%I', v_table)::regclass;
        FOR v_index IN SELECT i.indexrelid::regclass AS idx, c.relname::text AS name,
                              v_names[array_position(v_defs, split_part(pg_get_indexdef(i.indexrelid), ' USING ', 2))] AS old
                         FROM pg_index i JOIN pg_class c ON c.oid = i.indexrelid WHERE i.indrelid = v_new LOOP
            IF v_index.old IS NOT NULL AND v_index.old <> v_index.name THEN
                EXECUTE format('ALTER INDEX %s RENAME TO %I', v_index.idx, v_index.old);  -- a key's constraint too
            END IF;
        END LOOP;
        EXECUTE format('ALTER TABLE tgsis.%I OWNER TO %I', v_table, v_owner);
        EXECUTE format('COMMENT ON TABLE tgsis.%I IS %L', v_table, v_comment);
        PERFORM tgsis.create_hash_partitions(v_table, p_partitions, v_owner);
    END LOOP;
    IF v_swapped THEN  -- the row tables made again (a chunk table keeps its own rights)
        PERFORM tgsis.grant_model_tables(p_model);
        PERFORM tgsis.protect_model_tables(p_model);  -- LIKE ... INCLUDING ALL copies no policies
    END IF;
    RETURN v_tables;
END
$$;

REVOKE ALL ON FUNCTION tgsis.partition_model_storage(smallint, integer) FROM PUBLIC;

COMMENT ON FUNCTION tgsis.partition_model_storage(smallint, integer) IS
    'hash-partition the empty storage tables of a data model (1 to 5) by geoid in 2 to 1024 partitions (the chunk tables of tables stored in chunks with their data, versioned or not: tgsis.partition_chunk_storage) (at most what the server''s lock table holds: max_locks_per_transaction x (max_connections + max_prepared_transactions) locks, about 4 per partition of each table; TG100 naming the largest number otherwise), keeping their definitions, index names, comments, owner, rights and per-class row-level security; refused (and nothing changed) when a table holds rows, is versioned or partitioned already; returns the tables';
