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
    v_owner     name;
    v_comment   text;
    v_force     boolean;
    v_facedef   text;
    v_triggers  text[];
    v_trigger   text;
    v_names     text[];
    v_defs      text[];
    v_index     record;
    v_cols      text;
    v_sends     text;
    v_n         bigint;
    v_diff      bigint;
    v_new       regclass;
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
    SELECT string_agg(DISTINCT u, ', ') INTO v_users FROM (
        SELECT CASE WHEN d.classid = 'pg_rewrite'::regclass
                    THEN (SELECT 'view ' || r.ev_class::regclass::text FROM pg_rewrite r WHERE r.oid = d.objid)
                    ELSE pg_describe_object(d.classid, d.objid, 0) END
          FROM pg_depend d
         WHERE d.refclassid = 'pg_class'::regclass AND d.refobjid = v_store AND d.deptype = 'n'
           AND NOT (d.classid = 'pg_rewrite'::regclass AND v_face IS NOT NULL
                    AND EXISTS (SELECT FROM pg_rewrite r WHERE r.oid = d.objid AND r.ev_class = v_face))
           AND NOT (d.classid = 'pg_constraint'::regclass        -- the table's own checks name its columns
                    AND EXISTS (SELECT FROM pg_constraint c WHERE c.oid = d.objid AND c.conrelid = v_store))
           AND NOT (d.classid = 'pg_policy'::regclass            -- its own policies (copied)
                    AND EXISTS (SELECT FROM pg_policy p WHERE p.oid = d.objid AND p.polrelid = v_store))
           AND d.classid NOT IN ('pg_trigger'::regclass, 'pg_attrdef'::regclass)
        UNION ALL
        SELECT format('trigger %s on %s', t.tgname, t.tgrelid::regclass)
          FROM pg_trigger t
         WHERE NOT t.tgisinternal AND t.tgrelid = v_store
           AND NOT (v_versioned AND t.tgname IN ('tgsis_storage_write', 'tgsis_storage_rows', 'tgsis_storage_changes'))
    ) AS s(u);
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

    -- what the new table takes from the old one (read while they name it tgsis.<name>: the same text names the new one)
    SELECT c.relowner::regrole::name, obj_description(c.oid, 'pg_class'), c.relforcerowsecurity
      INTO v_owner, v_comment, v_force FROM pg_class c WHERE c.oid = v_store;
    IF v_face IS NOT NULL THEN
        SELECT format('CREATE OR REPLACE VIEW %s%s AS %s', v_face, coalesce(' WITH (' || array_to_string(c.reloptions, ', ') || ')', ''),
                      rtrim(pg_get_viewdef(c.oid), '; ' || chr(10)))
          INTO v_facedef FROM pg_class c WHERE c.oid = v_face;
    END IF;
    SELECT array_agg(pg_get_triggerdef(t.oid) ORDER BY t.tgname) INTO v_triggers
      FROM pg_trigger t WHERE NOT t.tgisinternal AND t.tgrelid = v_store;
    SELECT array_agg(c.relname::text ORDER BY c.relname), array_agg(split_part(pg_get_indexdef(i.indexrelid), ' USING ', 2) ORDER BY c.relname)
      INTO v_names, v_defs
      FROM pg_index i JOIN pg_class c ON c.oid = i.indexrelid WHERE i.indrelid = v_store;
    SELECT string_agg(quote_ident(a.attname), ', ' ORDER BY a.attnum),
           string_agg(CASE WHEN t.typcategory = 'A' THEN format('pg_catalog.array_send(%I)', a.attname)
                           WHEN t.typname = 'float8' THEN format('pg_catalog.float8send(%I)', a.attname)
                           WHEN t.typname = 'float4' THEN format('pg_catalog.float4send(%I)', a.attname)
                           ELSE format('%I::text', a.attname) END, ', ' ORDER BY a.attnum)
      INTO v_cols, v_sends
      FROM pg_attribute a JOIN pg_type t ON t.oid = a.atttypid
     WHERE a.attrelid = v_store AND a.attnum > 0 AND NOT a.attisdropped AND a.attgenerated = '';

    -- the new table beside the old one, partitioned, with the old one's rights
    EXECUTE format('ALTER TABLE tgsis.%I RENAME TO %I', v_name, v_old);
    EXECUTE format('CREATE TABLE tgsis.%I (LIKE tgsis.%I INCLUDING ALL) PARTITION BY HASH (geoid)', v_name, v_old);
    v_new := format('tgsis.%I', v_name)::regclass;
    EXECUTE format('ALTER TABLE %s OWNER TO %I', v_new, v_owner);
    EXECUTE format('COMMENT ON TABLE %s IS %L', v_new, v_comment);
    PERFORM tgsis.create_hash_partitions(v_name, p_partitions, v_owner);
    PERFORM tgsis.copy_relation_rights(v_store, v_new);
    IF v_force THEN
        EXECUTE format('ALTER TABLE %s FORCE ROW LEVEL SECURITY', v_new);
    END IF;

    -- the rows, moved (before the triggers are made: nothing to note) and verified, each column by its send form
    EXECUTE format('INSERT INTO %s (%s) SELECT %s FROM %s', v_new, v_cols, v_cols, v_store);
    GET DIAGNOSTICS v_n = ROW_COUNT;
    EXECUTE format('SELECT count(*) FROM ((SELECT %1$s FROM %2$s EXCEPT ALL SELECT %1$s FROM %3$s) '
                   'UNION ALL (SELECT %1$s FROM %3$s EXCEPT ALL SELECT %1$s FROM %2$s)) AS d', v_sends, v_store, v_new)
       INTO STRICT v_diff;
    IF v_diff <> 0 THEN
        RAISE EXCEPTION 'the partitioned storage of tgsis.% differs from its storage in % rows', quote_ident(p_table), v_diff
            USING ERRCODE = 'TG000', DETAIL = 'Nothing was changed.';
    END IF;

    -- the versioned view reads the new table; the old one goes, its index names and triggers are taken
    IF v_facedef IS NOT NULL THEN
        EXECUTE v_facedef;
    END IF;
    EXECUTE format('DROP TABLE %s', v_store);
    FOR v_index IN SELECT i.indexrelid::regclass AS idx, c.relname::text AS name,
                          v_names[array_position(v_defs, split_part(pg_get_indexdef(i.indexrelid), ' USING ', 2))] AS old
                     FROM pg_index i JOIN pg_class c ON c.oid = i.indexrelid WHERE i.indrelid = v_new LOOP
        IF v_index.old IS NOT NULL AND v_index.old <> v_index.name THEN
            EXECUTE format('ALTER INDEX %s RENAME TO %I', v_index.idx, v_index.old);  -- a key's constraint too
        END IF;
    END LOOP;
    FOREACH v_trigger IN ARRAY coalesce(v_triggers, '{}') LOOP
        EXECUTE v_trigger;
    END LOOP;
    RETURN v_n;
END
$$;

REVOKE ALL ON FUNCTION tgsis.partition_row_storage(text, integer, boolean) FROM PUBLIC;

COMMENT ON FUNCTION tgsis.partition_row_storage(text, integer, boolean) IS
    'hash-partition the row storage of model table tgsis.<table> (the table, or tgsis.<table>_ver when versioned) by geoid in 2 to 1024 partitions (the scheme of tgsis.partition_model_storage, which calls it), its rows moved and verified bit for bit (TG000 on a difference), the versioned view kept (reading the new table), the rights, row-level security and tgsis''s triggers of versioned storage made again as they were; TG202 when no plain table, not keyed by geoid first, or used by other objects (a user''s trigger included); p_check_only: lock and check only; returns the rows moved';
