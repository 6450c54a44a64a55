-- tgsis.alter_chunk_table(table, alters, properties, what): ALTER a class's property table stored in chunks in place, every chunk version at once.
-- Called by tgsis.alter_class_table (add_property, rename_property,
-- drop_property) for a property table stored in chunks
-- (tgsis.store_class_in_chunks), versioned or not: the chunk table is altered
-- itself, not converted to rows and back (two conversions of the whole table,
-- and none possible for a versioned class). Steps, in the caller's
-- transaction:
-- 1. the ALTERs run on the row definition <table>_shape (it holds no rows),
--    its new columns commented (tgsis.comment_property_columns); what the
--    chunks have no form for (a reserved name, no property left) is refused
--    by name (TG100) before the chunk table changes; a change of a column's
--    type is refused (TG100, not built). A vector property added or renamed
--    is known by its own CHECK there (tgsis.chunk_columns reads its size
--    from it until the caller writes the catalog).
-- 2. the face and the chunk view <table>_chunk_rows are dropped, with this
--    transaction's work tables of the face's writes; a user's view over the face
--    blocks the drop (2BP01, which the caller reports as TG202 naming it),
--    nothing changed; another session's work tables (of the face's row type)
--    live only in a transaction that wrote through the face (ON COMMIT DROP),
--    which holds the face's lock until it ends: waited for (the LOCK below),
--    never a session idle after its commit; the face's grants are kept.
-- 3. the chunk table, matched to the shape by column number: a new column is
--    a new array of the property's type (compression as tgsis.create_chunk_table
--    chooses it; a vector's two-dimensional, slots x k), added without a default (no rewrite of the table: a rewrite
--    is not MVCC-safe, an older REPEATABLE READ snapshot would read the table
--    empty) and filled by one UPDATE of every chunk version (MVCC: an older
--    snapshot keeps reading the versions it saw, the new array NULL there) with
--    the column's default at every present slot and NULL at every hole
--    (tgsis.chunk_filled: the contract's encoding; NULL everywhere when there
--    is no default; a vector's rows: the default vector, k NULLs at a hole,
--    as rows_to_chunks aggregates them); a renamed column is renamed;
--    a dropped one dropped. Other arrays are not touched (bit for bit).
-- 4. the chunk view and the face made again (tgsis.create_chunk_view,
--    tgsis.create_chunk_face: columns, comments, triggers, the versioned
--    write-right check), the face's grants given back.
-- The versioned registration (tgsis.versioned_tables: key, comment) names no
-- property and stays valid; the chunk table's guard triggers stay. Locks the
-- face and the chunk table ACCESS EXCLUSIVE first, in the order writers take
-- them: a writer in flight is waited for. Internal: runs with the caller's
-- rights (the owner of the class's tables).
CREATE FUNCTION tgsis.alter_chunk_table(p_table text, p_alters text[], p_properties jsonb DEFAULT '[]',
                                        p_what text DEFAULT NULL)
RETURNS void
LANGUAGE plpgsql
VOLATILE
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_reg     record;
    v_chunk   regclass;
    v_shape   regclass;
    v_face    regclass;
    v_before  record;
    v_cols    jsonb := '{}';   -- attnum -> [name, type] of the shape before the ALTERs
    v_new     jsonb := '{}';   -- attnum -> the default (SQL text, or null) of a column the ALTERs added
    v_alter   text;
    v_c       record;
    v_grants  aclitem[];
    v_acl     record;
    v_float   text;
    v_len     text;            -- a chunk version's length: an array of a property there before
BEGIN
    v_chunk := tgsis.chunk_table_of(p_table);  -- TG200 / TG100
    SELECT * INTO v_reg FROM tgsis.chunk_registry(p_table) r;
    v_shape := tgsis.row_shape(p_table);
    v_face := format('%I.%I', v_reg.schemaname, v_reg.tablename)::regclass;
    EXECUTE format('LOCK TABLE %s, %s IN ACCESS EXCLUSIVE MODE', v_face, v_chunk);
    FOR v_before IN SELECT a.attnum, a.attname, a.atttypid FROM pg_attribute a
                     WHERE a.attrelid = v_shape AND a.attnum > 0 AND NOT a.attisdropped LOOP
        v_cols := v_cols || jsonb_build_object(v_before.attnum::text, jsonb_build_array(v_before.attname, v_before.atttypid::oid));
    END LOOP;
    v_len := (SELECT CASE WHEN c.role = 'vector' THEN format('array_length(%I, 1)', c.name) ELSE format('cardinality(%I)', c.name) END
                FROM tgsis.chunk_columns(p_table) c WHERE c.role IN ('value', 'vector') ORDER BY c.colorder LIMIT 1);

    -- 1. the row definition; a new column's default is read right after its ADD (the callers drop it next)
    FOREACH v_alter IN ARRAY p_alters LOOP
        EXECUTE format('ALTER TABLE %s %s', v_shape, v_alter);
        FOR v_c IN SELECT a.attnum, pg_get_expr(d.adbin, d.adrelid) AS def FROM pg_attribute a
                     LEFT JOIN pg_attrdef d ON d.adrelid = a.attrelid AND d.adnum = a.attnum
                    WHERE a.attrelid = v_shape AND a.attnum > 0 AND NOT a.attisdropped
                      AND NOT v_cols ? a.attnum::text AND NOT v_new ? a.attnum::text LOOP
            v_new := v_new || jsonb_build_object(v_c.attnum::text, v_c.def);
        END LOOP;
    END LOOP;
    PERFORM tgsis.comment_property_columns(v_reg.schemaname, v_reg.tablename || '_shape', p_properties, p_what);
    -- (a vector property added or renamed: tgsis.chunk_columns reads its size from its own CHECK, the catalog
    -- naming it only after this call)
    PERFORM FROM tgsis.chunk_columns(p_table);  -- TG100 by name: a reserved name, none left
    IF EXISTS (SELECT FROM pg_attribute a WHERE a.attrelid = v_shape AND a.attnum > 0 AND NOT a.attisdropped
                 AND v_cols ? a.attnum::text AND (v_cols -> a.attnum::text ->> 1)::oid <> a.atttypid) THEN
        RAISE EXCEPTION 'the type of a property of % cannot be changed in chunks', tgsis.chunk_relation(p_table, '')
            USING ERRCODE = 'TG100', DETAIL = 'Only adding, renaming and dropping a property alter a chunk table in place.',
                  HINT = 'store the class in rows first (tgsis.store_class_in_rows)';
    END IF;

    -- 2. what reads the chunk table's columns goes; the face's grants are given back to the new face
    SELECT c.relacl INTO v_grants FROM pg_class c WHERE c.oid = v_face;
    -- this transaction's own work tables of the face's writes (tgsis.chunk_face_write: of the face's row type,
    -- emptied at each statement's end, ON COMMIT DROP) go with it; another session's exist only while its writing
    -- transaction is open, and the LOCK above waited for it to end
    EXECUTE format('DROP TABLE IF EXISTS %s, %s, %s, %s', tgsis.chunk_face_work(p_table, 'now'),
                   tgsis.chunk_face_work(p_table, 'queue'), tgsis.chunk_face_work(p_table, 'rows'), tgsis.chunk_face_work(p_table, 'dels'));
    EXECUTE format('DROP VIEW %s', v_face);  -- (its triggers with it; its row function is replaced by tgsis.create_chunk_face)
    EXECUTE format('DROP VIEW %s', tgsis.chunk_relation(p_table, '_chunk_rows'));

    -- 3. the chunk table: added columns first (their length from an array there before), renamed, dropped
    v_float := CASE WHEN EXISTS (SELECT FROM pg_settings WHERE name = 'default_toast_compression' AND 'lz4' = ANY (enumvals))
                    THEN 'lz4' ELSE 'pglz' END;
    FOR v_c IN SELECT a.attname, format_type(a.atttypid, a.atttypmod) AS typename, a.atttypid, v_new ->> a.attnum::text AS def,
                      c.role, c.typename AS elemtype, c.size
                 FROM pg_attribute a JOIN tgsis.chunk_columns(p_table) c ON c.name = a.attname
                WHERE a.attrelid = v_shape AND a.attnum > 0 AND NOT a.attisdropped AND v_new ? a.attnum::text
                ORDER BY a.attnum LOOP
        -- no default, no rewrite: only the catalog changes (a rewrite would show an older snapshot the table empty)
        -- (a vector: the same array type, two-dimensional)
        EXECUTE format('ALTER TABLE %s ADD COLUMN %I %s[] COMPRESSION %s', v_chunk, v_c.attname, v_c.elemtype,
                       CASE WHEN v_c.elemtype = 'double precision' THEN v_float ELSE 'pglz' END);
        -- filled by an UPDATE (MVCC: an older snapshot reads the chunk versions it saw, the new array NULL there);
        -- the other arrays' TOAST values are not copied (an unchanged external value keeps its pointer)
        IF v_c.role = 'vector' THEN
            -- the slots' vectors as the rows of a 2-D array, as rows_to_chunks aggregates them: the default's k
            -- values at a present slot, k NULLs at a hole (and everywhere when there is no default)
            EXECUTE format('UPDATE %1$s SET %2$I = (SELECT array_agg(CASE WHEN g.s = ANY (coalesce(holes, ''{}'')) OR (%3$s) IS NULL '
                           'THEN array_fill(NULL::%4$s, ARRAY[%5$s]) ELSE (%3$s)::%4$s[] END ORDER BY g.s) '
                           'FROM generate_series(1, %6$s) AS g(s))',
                           v_chunk, v_c.attname, coalesce(v_c.def, 'NULL'), v_c.elemtype, v_c.size, v_len);
        ELSE
            EXECUTE format('UPDATE %s SET %I = tgsis.chunk_filled((%s)::%s, %s, holes)', v_chunk,
                           v_c.attname, coalesce(v_c.def, 'NULL'), v_c.typename, v_len);
        END IF;
        EXECUTE format('COMMENT ON COLUMN %s.%I IS %L', v_chunk, v_c.attname,
                       format('%s per slot (NULL: no value, or a hole when holes lists the slot)',
                              coalesce(col_description(v_shape, (SELECT a.attnum FROM pg_attribute a
                                                                  WHERE a.attrelid = v_shape AND a.attname = v_c.attname)::integer),
                                       v_c.attname)));
    END LOOP;
    FOR v_c IN SELECT v_cols -> a.attnum::text ->> 0 AS old, a.attname AS new FROM pg_attribute a
                WHERE a.attrelid = v_shape AND a.attnum > 0 AND NOT a.attisdropped AND v_cols ? a.attnum::text
                  AND v_cols -> a.attnum::text ->> 0 <> a.attname LOOP
        EXECUTE format('ALTER TABLE %s RENAME COLUMN %I TO %I', v_chunk, v_c.old, v_c.new);
    END LOOP;
    FOR v_c IN SELECT e.value ->> 0 AS old FROM jsonb_each(v_cols) AS e
                WHERE NOT EXISTS (SELECT FROM pg_attribute a WHERE a.attrelid = v_shape AND a.attnum = e.key::smallint
                                                              AND NOT a.attisdropped) LOOP
        EXECUTE format('ALTER TABLE %s DROP COLUMN %I', v_chunk, v_c.old);
    END LOOP;

    -- 4. the chunk view and the face over the new columns, with the face's grants
    PERFORM tgsis.create_chunk_view(p_table);
    v_face := tgsis.create_chunk_face(p_table);
    FOR v_acl IN SELECT a.privilege_type, a.grantee FROM aclexplode(v_grants) AS a
                  WHERE a.grantee <> (SELECT c.relowner FROM pg_class c WHERE c.oid = v_face) LOOP
        EXECUTE format('GRANT %s ON %s TO %s', v_acl.privilege_type, v_face,
                       CASE WHEN v_acl.grantee = 0 THEN 'PUBLIC' ELSE quote_ident(pg_get_userbyid(v_acl.grantee)) END);
    END LOOP;
END
$$;

REVOKE ALL ON FUNCTION tgsis.alter_chunk_table(text, text[], jsonb, text) FROM PUBLIC;

COMMENT ON FUNCTION tgsis.alter_chunk_table(text, text[], jsonb, text) IS
    'ALTER a class''s property table stored in chunks in place (tgsis.alter_class_table: add, rename, drop a property), versioned or not: the ALTERs on <table>_shape, then the chunk table matched to it (a new array with the default at present slots and NULL at holes in every chunk version, a rename, a drop), the chunk view and the face made again with the face''s grants; TG100 by name for what chunks cannot hold, before the chunk table changes';
