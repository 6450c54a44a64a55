-- tgsis.swap_into_hash_partitions(relation, partitions, views): replace a storage table of tgsis by one of the same definition hash-partitioned by geoid, its rows moved and verified.
-- The shared part of tgsis.partition_chunk_storage and
-- tgsis.partition_row_storage (the callers lock, check what uses the table
-- with tgsis.relation_users, and make their own triggers again afterwards).
-- The table tgsis.<name> is renamed tgsis_old_<name>; a table LIKE it
-- INCLUDING ALL (columns, compression, defaults, generated columns, checks,
-- keys and indexes, comments) partitioned by HASH (geoid) takes its name,
-- owner, comment, p_partitions partitions (tgsis.create_hash_partitions),
-- grants, row-level security and policies (tgsis.copy_relation_rights); every
-- row is copied and verified (the new table holds exactly the old one's
-- rows, every column compared by its send form: doubles and arrays bit for
-- bit; TG000, and the caller's transaction changes nothing, otherwise); the
-- views p_views are made again by their own definitions (CREATE OR REPLACE:
-- their oids, grants, comments, triggers and the views over them kept),
-- reading the new table; the old one is dropped and its index names taken.
-- Internal: tgsis's owner, in the caller's transaction. Returns the rows moved.
CREATE FUNCTION tgsis.swap_into_hash_partitions(p_relation regclass, p_partitions integer, p_views regclass[] DEFAULT '{}')
RETURNS bigint
LANGUAGE plpgsql
VOLATILE
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_name     text;
    v_old      text;
    v_owner    name;
    v_comment  text;
    v_force    boolean;
    v_viewdefs text[];
    v_viewdef  text;
    v_names    text[];
    v_defs     text[];
    v_index    record;
    v_cols     text;
    v_sends    text;
    v_n        bigint;
    v_diff     bigint;
    v_new      regclass;
BEGIN
    SELECT c.relname::text, c.relowner::regrole::name, obj_description(c.oid, 'pg_class'), c.relforcerowsecurity
      INTO STRICT v_name, v_owner, v_comment, v_force
      FROM pg_class c WHERE c.oid = p_relation AND c.relnamespace = 'tgsis'::regnamespace;
    v_old := 'tgsis_old_' || v_name;
    -- what the new objects take from the old ones (read while they name the old table tgsis.<name>: the same
    -- text names the new one)
    v_viewdefs := ARRAY(SELECT format('CREATE OR REPLACE VIEW %s%s AS %s', c.oid::regclass,
                                      coalesce(' WITH (' || array_to_string(c.reloptions, ', ') || ')', ''),
                                      rtrim(pg_get_viewdef(c.oid), '; ' || chr(10)))
                          FROM unnest(p_views) WITH ORDINALITY AS v(oid, i) JOIN pg_class c ON c.oid = v.oid ORDER BY v.i);
    SELECT array_agg(c.relname::text ORDER BY c.relname), array_agg(split_part(pg_get_indexdef(i.indexrelid), ' USING ', 2) ORDER BY c.relname)
      INTO v_names, v_defs
      FROM pg_index i JOIN pg_class c ON c.oid = i.indexrelid WHERE i.indrelid = p_relation;
    SELECT string_agg(quote_ident(a.attname), ', ' ORDER BY a.attnum),
           string_agg(CASE WHEN t.typcategory = 'A' THEN format('pg_catalog.array_send(%I)', a.attname)
                           WHEN t.typname = 'float8' THEN format('pg_catalog.float8send(%I)', a.attname)
                           WHEN t.typname = 'float4' THEN format('pg_catalog.float4send(%I)', a.attname)
                           ELSE format('%I::text', a.attname) END, ', ' ORDER BY a.attnum)
      INTO v_cols, v_sends
      FROM pg_attribute a JOIN pg_type t ON t.oid = a.atttypid
     WHERE a.attrelid = p_relation AND a.attnum > 0 AND NOT a.attisdropped AND a.attgenerated = '';

    -- the new table beside the old one, partitioned, with the old one's rights
    EXECUTE format('ALTER TABLE tgsis.%I RENAME TO %I', v_name, v_old);
    EXECUTE format('CREATE TABLE tgsis.%I (LIKE tgsis.%I INCLUDING ALL) PARTITION BY HASH (geoid)', v_name, v_old);
    v_new := format('tgsis.%I', v_name)::regclass;
    EXECUTE format('ALTER TABLE %s OWNER TO %I', v_new, v_owner);
    EXECUTE format('COMMENT ON TABLE %s IS %L', v_new, v_comment);
    PERFORM tgsis.create_hash_partitions(v_name, p_partitions, v_owner);
    PERFORM tgsis.copy_relation_rights(p_relation, v_new);
    IF v_force THEN
        EXECUTE format('ALTER TABLE %s FORCE ROW LEVEL SECURITY', v_new);
    END IF;

    -- the rows, moved (before the callers' triggers are made again: nothing to note) and verified, each column
    -- by its send form
    EXECUTE format('INSERT INTO %s (%s) SELECT %s FROM %s', v_new, v_cols, v_cols, p_relation);
    GET DIAGNOSTICS v_n = ROW_COUNT;
    EXECUTE format('SELECT count(*) FROM ((SELECT %1$s FROM %2$s EXCEPT ALL SELECT %1$s FROM %3$s) '
                   'UNION ALL (SELECT %1$s FROM %3$s EXCEPT ALL SELECT %1$s FROM %2$s)) AS d', v_sends, p_relation, v_new)
       INTO STRICT v_diff;
    IF v_diff <> 0 THEN
        RAISE EXCEPTION 'the partitioned tgsis.% differs from the table it replaces in % rows', quote_ident(v_name), v_diff
            USING ERRCODE = 'TG000', DETAIL = 'Nothing was changed.';
    END IF;

    -- the views read the new table; the old one goes and its index names are taken
    FOREACH v_viewdef IN ARRAY v_viewdefs LOOP
        EXECUTE v_viewdef;
    END LOOP;
    EXECUTE format('DROP TABLE %s', p_relation);
    FOR v_index IN SELECT i.indexrelid::regclass AS idx, c.relname::text AS name,
                          v_names[array_position(v_defs, split_part(pg_get_indexdef(i.indexrelid), ' USING ', 2))] AS old
                     FROM pg_index i JOIN pg_class c ON c.oid = i.indexrelid WHERE i.indrelid = v_new LOOP
        IF v_index.old IS NOT NULL AND v_index.old <> v_index.name THEN
            EXECUTE format('ALTER INDEX %s RENAME TO %I', v_index.idx, v_index.old);  -- a key's constraint too
        END IF;
    END LOOP;
    RETURN v_n;
END
$$;

REVOKE ALL ON FUNCTION tgsis.swap_into_hash_partitions(regclass, integer, regclass[]) FROM PUBLIC;

COMMENT ON FUNCTION tgsis.swap_into_hash_partitions(regclass, integer, regclass[]) IS
    'replace a storage table tgsis.<name> by one LIKE it INCLUDING ALL hash-partitioned by geoid (tgsis.create_hash_partitions), with its owner, comment, rights, row-level security and policies, its rows moved and verified bit for bit (TG000 on a difference), the views p_views made again over it and its index names kept; the shared part of tgsis.partition_chunk_storage and tgsis.partition_row_storage; returns the rows moved';
