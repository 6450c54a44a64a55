-- tgsis.store_class_in_rows(class): store a class's property table as rows again, after tgsis.store_class_in_chunks.
-- The way back (docs/storage.md, "Property chunks: the contract"): the face
-- is dropped, <schema>.<class>_cellpros is a table again, made from the row
-- definition kept (<class>_cellpros_shape: columns, NOT NULLs, CHECKs, key,
-- comments) with the face's grants, filled from every chunk version and
-- verified value for value (tgsis.chunks_to_rows); then the chunk table, its
-- view and the shape go. A user's view over the face blocks it (PostgreSQL's
-- 2BP01 names the view; nothing changed). A versioned class is refused by
-- name (TG300, nothing changed): its way back is not built. tgsis_admin members; SECURITY
-- DEFINER as tgsis's owner owns the class's tables. Returns the rows written.
CREATE FUNCTION tgsis.store_class_in_rows(p_class text)
RETURNS bigint
LANGUAGE plpgsql
VOLATILE
SECURITY DEFINER
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_class tgsis.catalog;
    v_name  text;
    v_face  regclass;
    v_shape regclass;
    v_c     record;
    v_n     bigint;
BEGIN
    v_class := tgsis.class_for_change(p_class, 'store as rows the');  -- TG002, TG200
    v_name := format('%I.%I', v_class.schemaname, v_class.cellprotable);
    v_shape := to_regclass(tgsis.chunk_relation(v_name, '_shape'));
    IF v_shape IS NULL OR to_regclass(tgsis.chunk_relation(v_name, '_chunk')) IS NULL THEN
        RAISE EXCEPTION 'the properties of feature class % are not stored in chunks', coalesce(quote_literal(p_class), 'NULL')
            USING ERRCODE = 'TG200', DETAIL = 'Only what tgsis.store_class_in_chunks stored goes back to rows.';
    END IF;
    IF EXISTS (SELECT FROM tgsis.versioned_tables t WHERE t.schemaname = v_class.schemaname AND t.tablename = v_class.cellprotable) THEN
        RAISE EXCEPTION 'the properties of feature class % cannot be stored as rows again while the class is versioned', p_class
            USING ERRCODE = 'TG300',
                  DETAIL = format('%s holds the chunk versions of every version; the way back of a versioned class (its '
                                  '<table>_ver and versioned view made from them) is not built. Nothing was changed.',
                                  tgsis.chunk_relation(v_name, '_chunk')),
                  HINT = 'keep the properties in chunks, or store them as rows before versioning is enabled';
    END IF;
    v_face := v_name::regclass;
    EXECUTE format('LOCK TABLE %s IN SHARE ROW EXCLUSIVE MODE', tgsis.chunk_relation(v_name, '_chunk'));
    EXECUTE format('ALTER VIEW %s RENAME TO %I', v_face, v_class.cellprotable || '_face');
    EXECUTE format('CREATE TABLE %s (LIKE %s INCLUDING CONSTRAINTS INCLUDING COMMENTS)', v_name, v_shape);
    EXECUTE format('ALTER TABLE %s DROP CONSTRAINT %I', v_name, v_class.cellprotable || '_shape_holds_no_rows');
    FOR v_c IN SELECT con.conname, pg_get_constraintdef(con.oid) AS def FROM pg_constraint con
                WHERE con.conrelid = v_shape AND con.contype = 'p' LOOP
        EXECUTE format('ALTER TABLE %s ADD CONSTRAINT %I %s', v_name, v_class.cellprotable || '_pkey', v_c.def);
    END LOOP;
    EXECUTE format('COMMENT ON TABLE %s IS %L', v_name, split_part(obj_description(v_face, 'pg_class'), ', stored in chunks (', 1));
    PERFORM tgsis.copy_relation_rights(v_face, v_name::regclass);  -- the face's grants, grant options kept
    v_n := tgsis.chunks_to_rows(v_name);  -- verified (TG000: nothing changed)
    -- this session's tables of rows written through the face (tgsis.chunk_face_write) are of its row type; another
    -- session's block the DROP below by name (2BP01: nothing changed)
    EXECUTE format('DROP TABLE IF EXISTS pg_temp.%I, pg_temp.%I', 'tgsis_face_now_' || v_face::oid, 'tgsis_face_queue_' || v_face::oid);
    EXECUTE format('DROP VIEW %s', v_face);
    EXECUTE format('DROP VIEW %s', tgsis.chunk_relation(v_name, '_chunk_rows'));
    EXECUTE format('DROP TABLE %s', tgsis.chunk_relation(v_name, '_chunk'));
    EXECUTE format('DROP TABLE %s', v_shape);
    RETURN v_n;
END
$$;

REVOKE ALL ON FUNCTION tgsis.store_class_in_rows(text) FROM PUBLIC;
GRANT EXECUTE ON FUNCTION tgsis.store_class_in_rows(text) TO tgsis_admin;

COMMENT ON FUNCTION tgsis.store_class_in_rows(text) IS
    'store a class''s property table as rows again after tgsis.store_class_in_chunks (tgsis_admin members): the table made from its kept row definition with the face''s grants, filled from the chunks and verified (tgsis.chunks_to_rows), the face, chunk view, chunk table and shape dropped; TG200 when not stored in chunks, TG300 for a versioned class; returns the rows written';
