-- tgsis.move_row_indexes(from, to): the row table's own secondary indexes (e.g. model 5's per-point GiST
-- index md_vertex_point_idx, a user's index on a class's property table) moved, by name and definition, from
-- one relation to another of the same columns. The storage switches keep the row definition without rows
-- (tgsis.<table>_shape, tgsis.store_in_chunks, tgsis.store_class_in_chunks) and make the row table again from
-- it (tgsis.store_in_rows, tgsis.store_class_in_rows); without this, the way back made the key alone and a
-- box query read every point by a sequential scan (same answers, slower, nothing said).
-- Moved: every index that is not the key and backs no constraint (a key or unique constraint is part of the
-- definition, copied as such). Left: the versioning's own indexes (on revision, lastrevs or revclosed, and the
-- block index of a versioned simplex table on geoid and its vertex ids: tgsis.create_revision_indexes and
-- tgsis.enable_versioning_rel make them again with the versioning). An
-- empty shape keeps the index cheaply; the names stay those of the install (pg_dump/restore compares them).
CREATE FUNCTION tgsis.move_row_indexes(p_from regclass, p_to regclass)
RETURNS integer
LANGUAGE plpgsql
VOLATILE
SET search_path = pg_catalog, pg_temp
SET extra_float_digits = 1  -- a float constant of a partial index's predicate deparsed exactly, whatever the session's
AS $$
DECLARE
    v_idx   record;
    v_at    integer;
    v_on    text;
    v_n     integer := 0;
BEGIN
    FOR v_idx IN
        SELECT i.indexrelid::regclass AS idx, c.relname AS name, i.indisunique AS uniq, pg_get_indexdef(i.indexrelid) AS def
          FROM pg_index i
          JOIN pg_class c ON c.oid = i.indexrelid
         WHERE i.indrelid = p_from AND NOT i.indisprimary
           AND NOT EXISTS (SELECT FROM pg_constraint con WHERE con.conindid = i.indexrelid AND con.conrelid = p_from)
           AND NOT EXISTS (SELECT FROM pg_depend d
                             JOIN pg_attribute a ON a.attrelid = d.refobjid AND a.attnum = d.refobjsubid
                            WHERE d.classid = 'pg_class'::regclass AND d.objid = i.indexrelid
                              AND d.refclassid = 'pg_class'::regclass AND d.refobjid = p_from AND d.refobjsubid > 0
                              AND a.attname IN ('revision', 'lastrevs', 'revclosed'))
           -- the versioning's block index of a versioned simplex table (tgsis.create_revision_indexes: brin on geoid,
           -- the vertex or node ids and the instant or period), made again with the versioning, never kept aside
           AND NOT (EXISTS (SELECT FROM pg_attribute a WHERE a.attrelid = p_from AND a.attname = 'revision' AND NOT a.attisdropped)
                    AND (SELECT m.amname FROM pg_am m WHERE m.oid = c.relam) = 'brin'
                    AND NOT EXISTS (SELECT FROM unnest(i.indkey::int2[]) AS k(n)
                                      LEFT JOIN pg_attribute a ON a.attrelid = p_from AND a.attnum = k.n
                                     WHERE a.attname IS NULL
                                        OR NOT (a.attname IN ('geoid', 'times', 'timem') OR a.attname ~ '^(vrtxid|nodeid)[0-9]+$')))
         ORDER BY c.relname
    LOOP
        -- the definition's head, as pg_get_indexdef writes it: CREATE [UNIQUE] INDEX <name> ON [ONLY] <table,
        -- schema-qualified> USING ... (matched whole from the start: a quoted name may hold any text)
        v_on := format('CREATE %sINDEX %I ON %s USING ', CASE WHEN v_idx.uniq THEN 'UNIQUE ' ELSE '' END, v_idx.name, p_from);
        v_at := CASE WHEN starts_with(v_idx.def, v_on) THEN 1 ELSE 0 END;
        IF v_at = 0 THEN
            v_on := format('CREATE %sINDEX %I ON ONLY %s USING ', CASE WHEN v_idx.uniq THEN 'UNIQUE ' ELSE '' END, v_idx.name, p_from);
            v_at := CASE WHEN starts_with(v_idx.def, v_on) THEN 1 ELSE 0 END;
        END IF;
        IF v_at = 0 THEN
            RAISE EXCEPTION 'the index % of % cannot be moved to %', v_idx.idx, p_from, p_to
                USING ERRCODE = 'TG000',
                      DETAIL = format('Its definition does not name the table as expected: %s; nothing was changed.', v_idx.def),
                      HINT = 'Report this as a bug of tgsis; drop the index, switch the storage, and create it again.';
        END IF;
        EXECUTE format('DROP INDEX %s', v_idx.idx);
        EXECUTE format('CREATE %sINDEX %I ON %s USING ', CASE WHEN v_idx.uniq THEN 'UNIQUE ' ELSE '' END, v_idx.name, p_to)
                || substr(v_idx.def, length(v_on) + 1);
        v_n := v_n + 1;
    END LOOP;
    RETURN v_n;
END
$$;

REVOKE ALL ON FUNCTION tgsis.move_row_indexes(regclass, regclass) FROM PUBLIC;

COMMENT ON FUNCTION tgsis.move_row_indexes(regclass, regclass) IS
    'move the secondary indexes of a row table (not its key, no constraint''s, not the versioning''s: on revision, lastrevs or revclosed, or a versioned simplex table''s brin on geoid and its vertex ids) to another relation of the same columns, by name and definition, as the storage switches keep them on the row definition tgsis.<table>_shape and make them again on the way back; returns the indexes moved; TG000 when a definition does not name the table as expected';
