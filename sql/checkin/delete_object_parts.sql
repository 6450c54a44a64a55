-- tgsis.delete_object_parts(schema, table, keyfield, key, idfield, ids): delete some rows of one object in the session's version.
-- What a save of an edited mesh needs: the removed vertices, simplices or
-- property rows of one geometry, keyed by (key, id). On a versioned table
-- it is what the INSTEAD OF trigger does row by row, set-based: rows
-- written in the working revision go, older visible rows are closed by
-- appending it to their lastrevs, and an object locked by another version
-- is refused (TG303). Returns rows affected.
CREATE FUNCTION tgsis.delete_object_parts(p_schema text, p_table text, p_keyfield text, p_key bigint,
                                          p_idfield text, p_ids bigint[])
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
    IF cardinality(p_ids) IS NULL OR cardinality(p_ids) = 0 THEN
        RETURN 0;
    END IF;
    SELECT objectclass INTO v_class FROM tgsis.versioned_tables WHERE schemaname = p_schema AND tablename = p_table;
    IF NOT FOUND THEN
        EXECUTE format('DELETE FROM %I.%I WHERE %I = $1 AND %I = ANY ($2)', p_schema, p_table, p_keyfield, p_idfield)
          USING p_key, p_ids;
        GET DIAGNOSTICS v_deleted = ROW_COUNT;
        RETURN v_deleted;
    END IF;
    SELECT * INTO v_write FROM tgsis.write_revision();
    PERFORM tgsis.check_objects_unlocked(v_class, ARRAY[p_key::text]);
    EXECUTE format('DELETE FROM %I.%I WHERE %I = $1 AND %I = ANY ($2) AND revision = $3',
                   p_schema, p_table || '_ver', p_keyfield, p_idfield)
      USING p_key, p_ids, v_write.revision;
    GET DIAGNOSTICS v_deleted = ROW_COUNT;
    EXECUTE format('UPDATE %I.%I v SET lastrevs = v.lastrevs || $3
                     WHERE v.%I = $1 AND v.%I = ANY ($2) AND v.revision = ANY ($4) AND NOT (v.lastrevs && $4)',
                   p_schema, p_table || '_ver', p_keyfield, p_idfield)
      USING p_key, p_ids, v_write.revision, v_write.revisions;
    GET DIAGNOSTICS v_closed = ROW_COUNT;
    RETURN v_deleted + v_closed;
END
$$;

COMMENT ON FUNCTION tgsis.delete_object_parts(text, text, text, bigint, text, bigint[]) IS
    'delete the rows (key, id = any of ids) of one object from a table in the session''s version: plain DELETE, or on a versioned table the set-based equivalent of its trigger (TG303 when another version locked the object); returns rows affected';
