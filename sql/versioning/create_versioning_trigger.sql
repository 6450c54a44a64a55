-- tgsis.create_versioning_trigger(schema, table, keys, pkey, object class, object key): the INSTEAD OF trigger of a versioned view.
-- Generates <table>_ver_write() for the writable columns <table>_ver has now
-- (tgsis.versioning_trigger_source), with its comment, owner (the storage's)
-- and rights, the triggers on the view <table> (tgsis_versioning for each
-- row, tgsis_versioning_flush after each UPDATE statement), and the queue of
-- the rows an UPDATE keeping their keys writes when it ends,
-- <table>_ver_queue: UNLOGGED (it is empty outside a statement), its
-- columns of the writable columns' types and collations, the storage owner's
-- alone (the rights that default privileges gave are taken back). Called by
-- tgsis.create_versioned_view, and by an upgrade whose generated code
-- changed, after it dropped the old function with its trigger. Runs with the
-- caller's rights: the caller acts as the storage's owner.
CREATE FUNCTION tgsis.create_versioning_trigger(
    p_schema      text,
    p_table       text,
    p_keys        text[],
    p_pkey        text,
    p_objectclass text,
    p_keyfield    text)
RETURNS void
LANGUAGE plpgsql
VOLATILE
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_ver      regclass := format('%I.%I', p_schema, p_table || '_ver')::regclass;
    v_writable text[];
BEGIN
    SELECT array_agg(attname::text ORDER BY attnum) INTO v_writable
      FROM pg_attribute WHERE attrelid = v_ver AND attnum > 0 AND NOT attisdropped AND attgenerated = ''
       AND attname NOT IN ('revision', 'lastrevs', 'revclosed');
    EXECUTE tgsis.versioning_trigger_source(p_schema, p_table, p_keys, v_writable, p_pkey, p_objectclass, p_keyfield);
    PERFORM tgsis.create_versioning_queue(p_schema, p_table, v_writable);
    EXECUTE format('COMMENT ON FUNCTION %I.%I() IS %L', p_schema, p_table || '_ver_write',
                   format('tgsis versioning: INSTEAD OF trigger routing writes on %s.%s into %s', p_schema, p_table,
                          p_table || '_ver'));
    EXECUTE format('CREATE TRIGGER %I INSTEAD OF INSERT OR UPDATE OR DELETE ON %I.%I FOR EACH ROW EXECUTE FUNCTION %I.%I()',
                   'tgsis_versioning', p_schema, p_table, p_schema, p_table || '_ver_write');
    EXECUTE format('CREATE TRIGGER %I AFTER UPDATE ON %I.%I FOR EACH STATEMENT EXECUTE FUNCTION %I.%I()',
                   'tgsis_versioning_flush', p_schema, p_table, p_schema, p_table || '_ver_write');
    EXECUTE format('ALTER FUNCTION %I.%I() OWNER TO %I', p_schema, p_table || '_ver_write',
                   (SELECT pg_get_userbyid(c.relowner) FROM pg_class c WHERE c.oid = v_ver));
    EXECUTE format('REVOKE ALL ON FUNCTION %I.%I() FROM PUBLIC', p_schema, p_table || '_ver_write');
END
$$;

COMMENT ON FUNCTION tgsis.create_versioning_trigger(text, text, text[], text, text, text) IS
    'create <table>_ver_write() (tgsis.versioning_trigger_source, for the writable columns of <table>_ver), its comment, owner and rights, its queue <table>_ver_queue (tgsis.create_versioning_queue), and the triggers of the view <table>: tgsis_versioning (INSTEAD OF, each row) and tgsis_versioning_flush (after each UPDATE)';
