-- tgsis.delete_object_rows(schema, table, keyfield, keys): delete objects' rows in the session's version, set-based.
-- On a versioned table this is what the INSTEAD OF trigger does row by row,
-- in two statements: rows written in the working revision go, older visible
-- rows get the working revision appended to lastrevs. Returns rows affected.
CREATE FUNCTION tgsis.delete_object_rows(p_schema text, p_table text, p_keyfield text, p_keys bigint[])
RETURNS bigint
LANGUAGE plpgsql
VOLATILE
AS $$
DECLARE
    v_write   record;
    v_deleted bigint;
    v_closed  bigint;
    v_class   text;
BEGIN
    SELECT objectclass INTO v_class FROM tgsis.versioned_tables WHERE schemaname = p_schema AND tablename = p_table;
    IF NOT FOUND THEN
        EXECUTE format('DELETE FROM %I.%I WHERE %I = ANY ($1)', p_schema, p_table, p_keyfield) USING p_keys;
        GET DIAGNOSTICS v_deleted = ROW_COUNT;
        RETURN v_deleted;
    END IF;
    SELECT * INTO v_write FROM tgsis.write_revision();
    PERFORM tgsis.check_objects_unlocked(v_class, p_keys::text[]);
    EXECUTE format('DELETE FROM %I.%I WHERE %I = ANY ($1) AND revision = $2', p_schema, p_table || '_ver', p_keyfield)
      USING p_keys, v_write.revision;
    GET DIAGNOSTICS v_deleted = ROW_COUNT;
    EXECUTE format('UPDATE %I.%I v SET lastrevs = v.lastrevs || $2
                     WHERE v.%I = ANY ($1) AND v.revision = ANY ($3) AND NOT (v.lastrevs && $3)',
                   p_schema, p_table || '_ver', p_keyfield)
      USING p_keys, v_write.revision, v_write.revisions;
    GET DIAGNOSTICS v_closed = ROW_COUNT;
    RETURN v_deleted + v_closed;
END
$$;

COMMENT ON FUNCTION tgsis.delete_object_rows(text, text, text, bigint[]) IS
    'delete the rows of objects (keyfield = any of keys) from a table in the session''s version: plain DELETE, or on a versioned table the set-based equivalent of its trigger; returns rows affected';
