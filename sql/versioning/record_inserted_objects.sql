-- tgsis.record_inserted_objects(): AFTER INSERT statement trigger on every <table>_ver: note the objects a statement wrote rows of.
-- Direct writes into storage (the client's COPY upload, a script's INSERT,
-- tgsis's own set-based copies) are noted here, once per statement, from the
-- statement's transition table: each (revision, object) of the new rows, and
-- of their lastrevs when a row came in closed. The trigger's WHEN leaves out
-- the single-row inserts of the views' INSTEAD OF triggers (the storage's
-- owner writing inside a trigger), which note their objects themselves
-- (tgsis.record_changed_objects) after one probe per row: a statement
-- trigger with a transition table, run for each row, measured some 40 us a
-- row on a path that costs about 150 us a row in all.
-- The usual statement (an upload) writes one object in one revision: one
-- pass that stops at the first row of another revision or object, or a
-- closed one, says so, and only statements that mix them pay for grouping
-- their rows (docs/performance.md has what each costs an upload). No JIT:
-- the transition table of an upload is large enough to trigger it, and
-- compiling costs more than the pass. Trigger argument: the object key column.
CREATE FUNCTION tgsis.record_inserted_objects()
RETURNS trigger
LANGUAGE plpgsql
VOLATILE
SECURITY DEFINER
SET search_path = pg_catalog, pg_temp
SET jit = off
AS $$
DECLARE
    v_table    text := coalesce(TG_ARGV[1], left(TG_TABLE_NAME, -4));  -- (given for tgsis.<table>_chunk)
    v_revision integer;
    v_key      text;
    v_mixed    boolean;
    v_type     oid;        -- the key's type: keys are noted as their canonical text (tgsis.object_key_sql)
BEGIN
    -- keys are cast to text here, as tgsis's owner: only a built-in type's cast (TG100 otherwise)
    PERFORM tgsis.check_key_type(TG_RELID, TG_ARGV[0]);
    v_type := (SELECT a.atttypid FROM pg_catalog.pg_attribute a WHERE a.attrelid = TG_RELID AND a.attname = TG_ARGV[0]);
    EXECUTE format(
        'WITH f AS (SELECT n.revision, n.%1$I AS k FROM tgsis_new_rows n LIMIT 1)
         SELECT f.revision, %2$s,
                EXISTS (SELECT FROM tgsis_new_rows n WHERE n.revision <> f.revision OR n.%1$I <> f.k OR n.revclosed)
           FROM f', TG_ARGV[0], tgsis.object_key_sql(v_type, 'f.k'))
       INTO v_revision, v_key, v_mixed;
    IF v_revision IS NULL THEN
        RETURN NULL;  -- no row
    ELSIF NOT v_mixed THEN
        PERFORM tgsis.note_changed_objects(TG_TABLE_SCHEMA, v_table, v_revision, ARRAY[v_key]);
        RETURN NULL;
    END IF;
    -- several revisions or objects, or closed rows: each pair once (keys grouped in their own type, cast once)
    EXECUTE format(
        'INSERT INTO tgsis.revision_objects (revision, schemaname, tablename, objectkey)
         SELECT d.revision, $1, $2, %2$s
           FROM (SELECT n.revision, n.%1$I AS k FROM tgsis_new_rows n WHERE n.revision <> 0 GROUP BY 1, 2
                 UNION
                 SELECT l.r, n.%1$I FROM tgsis_new_rows n, pg_catalog.unnest(n.lastrevs) AS l(r)
                  WHERE n.revclosed AND l.r <> 0) AS d
          WHERE NOT EXISTS (SELECT FROM tgsis.revision_objects o
                             WHERE o.revision = d.revision AND o.schemaname = $1 AND o.tablename = $2
                               AND o.objectkey = %2$s)', TG_ARGV[0], tgsis.object_key_sql(v_type, 'd.k'))
        USING TG_TABLE_SCHEMA, v_table;
    RETURN NULL;
END
$$;

COMMENT ON FUNCTION tgsis.record_inserted_objects() IS
    'AFTER INSERT statement trigger of <table>_ver storage (transition table tgsis_new_rows): note the objects the statement wrote rows of, per revision, in tgsis.revision_objects (not for the views'' row triggers, which note their own)';
