-- tgsis.delete_object_rows(schema, table, keyfield, keys, idfield, ids): delete objects' rows (or some of them) in the session's version, set-based.
-- A plain table's rows are deleted with the caller's rights. On a versioned
-- table this is what the INSTEAD OF trigger does row by row, in two
-- statements (tgsis.close_object_rows, with tgsis's rights after the same
-- checks): rows written in the working revision go, older visible rows get
-- the working revision appended to lastrevs, and objects locked by another
-- version are refused (TG303). With p_idfield and p_ids only the
-- rows whose id is one of p_ids go: the removed vertices, simplices or
-- property rows of an edited mesh (tgsis.save_feature). A class's property
-- table stored in chunks: some rows of an object through its face, which
-- rewrites their chunks in the working revision with the caller's rights;
-- whole objects while unversioned by tgsis.write_property_rows, each
-- object's rows at once (the face's checks for the set, each touched chunk
-- written once; a temporal class's, keyed by instants too, through its
-- face). Returns rows affected.
CREATE FUNCTION tgsis.delete_object_rows(p_schema text, p_table text, p_keyfield text, p_keys bigint[],
                                         p_idfield text DEFAULT NULL, p_ids bigint[] DEFAULT NULL)
RETURNS bigint
LANGUAGE plpgsql
VOLATILE
AS $$
DECLARE
    v_deleted bigint;
    v_where   text;
    v_key     bigint;
    v_ids     bigint[];
BEGIN
    IF to_regclass(format('%I.%I', p_schema, p_table)) IS NULL THEN
        RAISE EXCEPTION 'table %.% does not exist', quote_ident(p_schema), quote_ident(p_table)
            USING ERRCODE = 'TG200';
    END IF;
    IF (p_idfield IS NULL) <> (p_ids IS NULL) THEN
        RAISE EXCEPTION 'delete_object_rows takes an id column and ids together, or neither'
            USING ERRCODE = 'TG100', DETAIL = format('idfield %s, ids %s', coalesce(p_idfield, 'NULL'),
                                                      coalesce(p_ids::text, 'NULL'));
    END IF;
    IF p_ids IS NOT NULL AND cardinality(p_ids) = 0 THEN
        RETURN 0;
    END IF;
    v_where := format('%I = ANY ($1)', p_keyfield)
               || CASE WHEN p_idfield IS NOT NULL THEN format(' AND %I = ANY ($4)', p_idfield) ELSE '' END;
    -- a feature class's property table stored in chunks (tgsis.store_class_in_chunks): some rows of an object go
    -- through its face, whose trigger rewrites their chunks in the working revision (tgsis.chunk_face_write, the
    -- caller's rights); whole objects while it is not versioned go by the chunk writer, each object's rows at
    -- once (tgsis.write_property_rows: the face's checks for the set, each chunk written once, not a trigger call
    -- per row); while versioned they are closed as chunk versions (tgsis.close_object_rows)
    -- (a temporal class's property table, keyed by its instants too, goes through its face: its trigger writes each
    -- touched chunk once at the statement's end)
    IF p_schema <> 'tgsis' AND p_idfield IS NULL AND tgsis.stored_in_chunks(p_schema, p_table)
       AND NOT EXISTS (SELECT FROM tgsis.versioned_tables WHERE schemaname = p_schema AND tablename = p_table)
       AND EXISTS (SELECT FROM tgsis.catalog c WHERE c.schemaname = p_schema AND c.timemodel = 'STATIC'
                      AND p_table IN (c.cellprotable, c.otherprotable)) THEN
        v_deleted := 0;
        FOR v_key IN SELECT DISTINCT k FROM unnest(p_keys) AS k WHERE k IS NOT NULL ORDER BY 1 LOOP
            -- (a class's property table is keyed (_geoid, _idx))
            EXECUTE format('SELECT array_agg(_idx ORDER BY _idx) FROM %I.%I WHERE %I = $1', p_schema, p_table, p_keyfield)
               INTO v_ids USING v_key;
            CONTINUE WHEN v_ids IS NULL;
            -- (tgsis.write_property_rows is of a later layer, chunks/: named through %I, as merge_write_keyed_rows does)
            EXECUTE format('SELECT tgsis.%I(%L, $1, $2, ARRAY[]::%I.%I[])',
                           'write_property_rows', format('%I.%I', p_schema, p_table), p_schema, p_table)
              USING v_key, v_ids;
            v_deleted := v_deleted + cardinality(v_ids);
        END LOOP;
        RETURN v_deleted;
    END IF;
    IF p_schema <> 'tgsis' AND tgsis.stored_in_chunks(p_schema, p_table)
       AND (p_idfield IS NOT NULL
            OR NOT EXISTS (SELECT FROM tgsis.versioned_tables WHERE schemaname = p_schema AND tablename = p_table)) THEN
        EXECUTE format('DELETE FROM %I.%I WHERE %s', p_schema, p_table, v_where)
          USING p_keys, NULL::integer, NULL::integer[], p_ids;
        GET DIAGNOSTICS v_deleted = ROW_COUNT;
        RETURN v_deleted;
    END IF;
    IF NOT EXISTS (SELECT FROM tgsis.versioned_tables WHERE schemaname = p_schema AND tablename = p_table) THEN
        -- stored in chunks: whole objects' chunks go at once (every chunk version is revision 0, the one state);
        -- never a whole chunk for some of its rows (tgsis.close_object_rows refuses that as for versioned storage)
        IF tgsis.stored_in_chunks(p_schema, p_table) THEN
            IF p_idfield IS NOT NULL THEN
                RETURN tgsis.close_object_rows(p_schema, p_table, p_keyfield, p_keys, p_idfield, p_ids);  -- TG100
            END IF;
            EXECUTE format('DELETE FROM %s WHERE %I = ANY ($1)', tgsis.storage_table(p_schema, p_table), p_keyfield)
              USING p_keys;
            GET DIAGNOSTICS v_deleted = ROW_COUNT;
            RETURN v_deleted;
        END IF;
        EXECUTE format('DELETE FROM %I.%I WHERE %s', p_schema, p_table, v_where)
          USING p_keys, NULL::integer, NULL::integer[], p_ids;
        GET DIAGNOSTICS v_deleted = ROW_COUNT;
        RETURN v_deleted;
    END IF;
    RETURN tgsis.close_object_rows(p_schema, p_table, p_keyfield, p_keys, p_idfield, p_ids);
END
$$;

COMMENT ON FUNCTION tgsis.delete_object_rows(text, text, text, bigint[], text, bigint[]) IS
    'delete the rows of objects (keyfield = any of keys; with idfield and ids only those rows) from a table in the session''s version: plain DELETE, or on a versioned table the set-based equivalent of its trigger (TG303 when another version locked an object); returns rows affected';
