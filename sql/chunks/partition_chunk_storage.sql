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
    v_view      regclass;
    v_kind      "char";
    v_users     text;
    v_owner     name;
    v_comment   text;
    v_facedef   text;
    v_viewdef   text;
    v_names     text[];
    v_defs      text[];
    v_index     record;
    v_cols      text;
    v_sends     text;
    v_n         bigint;
    v_diff      bigint;
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
    -- block the swap or be lost
    SELECT string_agg(DISTINCT u, ', ') INTO v_users FROM (
        SELECT CASE WHEN d.classid = 'pg_rewrite'::regclass
                    THEN (SELECT 'view ' || r.ev_class::regclass::text FROM pg_rewrite r WHERE r.oid = d.objid)
                    ELSE pg_describe_object(d.classid, d.objid, 0) END AS u
          FROM pg_depend d
         WHERE d.refclassid = 'pg_class'::regclass AND d.refobjid = v_chunk AND d.deptype = 'n'
           AND NOT (d.classid = 'pg_rewrite'::regclass
                    AND EXISTS (SELECT FROM pg_rewrite r WHERE r.oid = d.objid AND r.ev_class IN (v_face, v_view)))
           AND NOT (d.classid = 'pg_constraint'::regclass
                    AND EXISTS (SELECT FROM pg_constraint c WHERE c.oid = d.objid AND c.conrelid = v_chunk))
           AND NOT (d.classid = 'pg_policy'::regclass
                    AND EXISTS (SELECT FROM pg_policy p WHERE p.oid = d.objid AND p.polrelid = v_chunk))
           AND d.classid NOT IN ('pg_trigger'::regclass, 'pg_attrdef'::regclass)
        UNION ALL
        -- triggers other than the guards of versioned storage and the insert check (made again)
        SELECT format('trigger %s on %s', t.tgname, t.tgrelid::regclass)
          FROM pg_trigger t
         WHERE NOT t.tgisinternal AND t.tgrelid = v_chunk
           AND t.tgname NOT IN ('tgsis_storage_write', 'tgsis_storage_rows', 'tgsis_storage_changes', 'tgsis_chunk_insert')
    ) AS s(u);
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

    -- what the new objects take from the old ones
    SELECT c.relowner::regrole::name, obj_description(c.oid, 'pg_class') INTO v_owner, v_comment FROM pg_class c WHERE c.oid = v_chunk;
    -- (read while they name the old table tgsis.<table>_chunk: the same text names the new one)
    SELECT format('CREATE OR REPLACE VIEW %s%s AS %s', v_face, coalesce(' WITH (' || array_to_string(c.reloptions, ', ') || ')', ''),
                  rtrim(pg_get_viewdef(c.oid), '; ' || chr(10)))
      INTO v_facedef FROM pg_class c WHERE c.oid = v_face;
    SELECT format('CREATE OR REPLACE VIEW %s%s AS %s', v_view, coalesce(' WITH (' || array_to_string(c.reloptions, ', ') || ')', ''),
                  rtrim(pg_get_viewdef(c.oid), '; ' || chr(10)))
      INTO v_viewdef FROM pg_class c WHERE c.oid = v_view;
    SELECT array_agg(c.relname::text ORDER BY c.relname), array_agg(split_part(pg_get_indexdef(i.indexrelid), ' USING ', 2) ORDER BY c.relname)
      INTO v_names, v_defs
      FROM pg_index i JOIN pg_class c ON c.oid = i.indexrelid WHERE i.indrelid = v_chunk;
    SELECT string_agg(quote_ident(a.attname), ', ' ORDER BY a.attnum),
           string_agg(CASE WHEN t.typcategory = 'A' THEN format('pg_catalog.array_send(%I)', a.attname)
                           ELSE format('%I::text', a.attname) END, ', ' ORDER BY a.attnum)
      INTO v_cols, v_sends
      FROM pg_attribute a JOIN pg_type t ON t.oid = a.atttypid
     WHERE a.attrelid = v_chunk AND a.attnum > 0 AND NOT a.attisdropped AND a.attgenerated = '';

    -- the new chunk table beside the old one, partitioned, with the old one's rights
    EXECUTE format('ALTER TABLE tgsis.%I RENAME TO %I', v_name, v_old);
    EXECUTE format('CREATE TABLE tgsis.%I (LIKE tgsis.%I INCLUDING ALL) PARTITION BY HASH (geoid)', v_name, v_old);
    v_new := format('tgsis.%I', v_name)::regclass;
    EXECUTE format('ALTER TABLE %s OWNER TO %I', v_new, v_owner);
    EXECUTE format('COMMENT ON TABLE %s IS %L', v_new, v_comment);
    PERFORM tgsis.create_hash_partitions(v_name, p_partitions, v_owner);
    PERFORM tgsis.copy_relation_rights(v_chunk, v_new);
    IF (SELECT c.relforcerowsecurity FROM pg_class c WHERE c.oid = v_chunk) THEN
        EXECUTE format('ALTER TABLE %s FORCE ROW LEVEL SECURITY', v_new);
    END IF;

    -- the chunk versions, moved and verified: the same rows, each column by its send form (doubles bit for bit)
    EXECUTE format('INSERT INTO %s (%s) SELECT %s FROM %s', v_new, v_cols, v_cols, v_chunk);
    GET DIAGNOSTICS v_n = ROW_COUNT;
    EXECUTE format('SELECT count(*) FROM ((SELECT %1$s FROM %2$s EXCEPT ALL SELECT %1$s FROM %3$s) '
                   'UNION ALL (SELECT %1$s FROM %3$s EXCEPT ALL SELECT %1$s FROM %2$s)) AS d', v_sends, v_chunk, v_new)
       INTO STRICT v_diff;
    IF v_diff <> 0 THEN
        RAISE EXCEPTION 'the partitioned chunk table of tgsis.% differs from its chunk table in % chunk versions', quote_ident(p_table), v_diff
            USING ERRCODE = 'TG000', DETAIL = 'Nothing was changed.';
    END IF;

    -- the face and the chunk view read the new table; the old one goes and its index names are taken
    EXECUTE v_facedef;
    EXECUTE v_viewdef;
    EXECUTE format('DROP TABLE %s', v_chunk);
    FOR v_index IN SELECT i.indexrelid::regclass AS idx, c.relname::text AS name,
                          v_names[array_position(v_defs, split_part(pg_get_indexdef(i.indexrelid), ' USING ', 2))] AS old
                     FROM pg_index i JOIN pg_class c ON c.oid = i.indexrelid WHERE i.indrelid = v_new LOOP
        IF v_index.old IS NOT NULL AND v_index.old <> v_index.name THEN
            EXECUTE format('ALTER INDEX %s RENAME TO %I', v_index.idx, v_index.old);  -- a key's constraint too
        END IF;
    END LOOP;
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
