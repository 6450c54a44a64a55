-- tgsis.create_versioning_queue(schema, table, writable columns): the table <table>_ver_queue.
-- An UPDATE through the versioned view <table> that keeps its rows' keys
-- queues each row's new and old values there, and <table>_ver_write(),
-- fired after the statement, writes them all at once
-- (tgsis.versioning_trigger_source says how). The queue holds rows only
-- while a statement runs, so it is UNLOGGED. The rows a flush writes are
-- those of its transaction and of the view's generation (the setting
-- tgsis.queue_<view oid>, which each flush of the view counts up), found
-- through an index on the two: the rows earlier statements of a long
-- transaction queued and deleted stay in the table as dead rows until it
-- ends, and a scan of the whole queue would visit all of them (a
-- transaction of n small UPDATEs, from the client or from a loop in one DO
-- block, would cost n^2).
-- Its columns keep the types,
-- typmods and collations of the storage's (the comparison with the stored
-- row is of binary images: record_image_eq). It is the storage owner's
-- alone: a role allowed to fill it could have any values written. Runs with
-- the caller's rights, as tgsis.create_versioning_trigger.
CREATE FUNCTION tgsis.create_versioning_queue(
    p_schema   text,
    p_table    text,
    p_columns  text[])
RETURNS void
LANGUAGE plpgsql
VOLATILE
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_ver     regclass := format('%I.%I', p_schema, p_table || '_ver')::regclass;
    v_queue   text := p_table || '_ver_queue';
    v_columns text;
    v_grantee oid;
    v_i       integer;
BEGIN
    SELECT string_agg(format('%s%s %s%s', s.side, u.o, format_type(a.atttypid, a.atttypmod),
                             CASE WHEN a.attcollation <> 0
                                  THEN format(' COLLATE %I.%I', cn.nspname, co.collname) ELSE '' END),
                      ', ' ORDER BY s.side, u.o)
      INTO v_columns
      FROM unnest(p_columns) WITH ORDINALITY AS u(name, o)
     CROSS JOIN (VALUES ('n'), ('o')) AS s(side)
      JOIN pg_attribute a ON a.attrelid = v_ver AND a.attname = u.name AND NOT a.attisdropped
      LEFT JOIN pg_collation co ON co.oid = a.attcollation
      LEFT JOIN pg_namespace cn ON cn.oid = co.collnamespace;
    EXECUTE format('CREATE UNLOGGED TABLE %I.%I (tgsis_xact xid8 NOT NULL, tgsis_generation bigint NOT NULL, %s)',
                   p_schema, v_queue, v_columns);
    -- named by PostgreSQL (unique, within the length of a name)
    EXECUTE format('CREATE INDEX ON %I.%I (tgsis_xact, tgsis_generation)', p_schema, v_queue);
    EXECUTE format('ALTER TABLE %I.%I OWNER TO %I', p_schema, v_queue,
                   (SELECT pg_get_userbyid(c.relowner) FROM pg_class c WHERE c.oid = v_ver));
    -- rights that default privileges gave: taken back
    FOR v_grantee IN
        SELECT DISTINCT a.grantee FROM pg_class c, aclexplode(c.relacl) AS a
         WHERE c.oid = format('%I.%I', p_schema, v_queue)::regclass AND a.grantee <> c.relowner
    LOOP
        EXECUTE format('REVOKE ALL ON %I.%I FROM %s', p_schema, v_queue,
                       CASE WHEN v_grantee = 0 THEN 'PUBLIC' ELSE quote_ident(pg_get_userbyid(v_grantee)) END);
    END LOOP;
    EXECUTE format('COMMENT ON TABLE %I.%I IS %L', p_schema, v_queue,
                   format('tgsis versioning: the rows an UPDATE on %s.%s keeping their keys changes, written to %s when the statement ends; empty outside a statement',
                          p_schema, p_table, p_table || '_ver'));
    EXECUTE format('COMMENT ON COLUMN %I.%I.tgsis_xact IS %L', p_schema, v_queue,
                   'pg_current_xact_id() of the transaction that queued the row');
    EXECUTE format('COMMENT ON COLUMN %I.%I.tgsis_generation IS %L', p_schema, v_queue,
                   'how many times the transaction had flushed the view''s queue before (setting tgsis.queue_<view oid>): the next flush of the view writes the rows of its generation');
    EXECUTE format('COMMENT ON INDEX %s IS %L',
                   (SELECT i.indexrelid::regclass::text FROM pg_index i
                     WHERE i.indrelid = format('%I.%I', p_schema, v_queue)::regclass),
                   'tgsis versioning: the rows of one flush, without visiting those earlier flushes of the transaction deleted');
    FOR v_i IN 1 .. cardinality(p_columns) LOOP
        EXECUTE format('COMMENT ON COLUMN %I.%I.%I IS %L', p_schema, v_queue, 'n' || v_i,
                       format('the new value of %s', p_columns[v_i]));
        EXECUTE format('COMMENT ON COLUMN %I.%I.%I IS %L', p_schema, v_queue, 'o' || v_i,
                       format('the value of %s the statement read', p_columns[v_i]));
    END LOOP;
END
$$;

COMMENT ON FUNCTION tgsis.create_versioning_queue(text, text, text[]) IS
    'create <table>_ver_queue, the owner-only UNLOGGED queue of the rows an UPDATE keeping their keys writes through the view <table> when it ends: n<i> and o<i>, the new and read values of the i-th writable column of <table>_ver';
