-- tgsis.store_class_in_rows(class): store a class's property tables as rows again, after tgsis.store_class_in_chunks.
-- The way back (docs/storage.md, "Property chunks: the contract"), for each
-- of the class's property tables in chunks (cellprotable and otherprotable,
-- in one transaction): the face
-- is dropped, <schema>.<class>_cellpros is a table again, made from the row
-- definition kept (<class>_cellpros_shape: columns, NOT NULLs, CHECKs, key,
-- comments) with the face's grants, filled from every chunk version and
-- verified value for value (tgsis.chunks_to_rows); then the chunk table, its
-- view and the shape go. A versioned class goes back with its history: the
-- table, empty, is versioned again by tgsis.enable_versioning_rel (its
-- <table>_ver, versioned view, queue, write function and runner made as
-- enable_feature_versioning makes them, the registration's other fields --
-- when and by whom versioning was enabled, the table's comment -- kept), every
-- chunk version written as row versions of <table>_ver with its revision and
-- lastrevs and verified against every version's and revision's set
-- (tgsis.check_chunk_conversion) before the chunks go, the conflicts' marks
-- renewed (solved conflicts stay solved), as tgsis.store_class_in_chunks
-- does the other way. Row versions a chunk's versions share are repeated per
-- version (tgsis.chunks_to_rows): what every set sees is kept, not the count
-- of row versions. A user's view over the face blocks it (PostgreSQL's 2BP01
-- names the view; nothing changed). tgsis_admin members; SECURITY DEFINER as
-- tgsis's owner owns the class's tables. Returns the rows written.
CREATE FUNCTION tgsis.store_class_in_rows(p_class text)
RETURNS bigint
LANGUAGE plpgsql
VOLATILE
SECURITY DEFINER
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_class  tgsis.catalog;
    v_tables text[];   -- the property tables in chunks: cellprotable, then otherprotable
    v_tab    text;
    v_name   text;
    v_face   regclass;
    v_shape  regclass;
    v_c      record;
    v_n      bigint := 0;
    v_versioned tgsis.versioned_tables;
    v_marks  jsonb;
BEGIN
    v_class := tgsis.class_for_change(p_class, 'store as rows the');  -- TG002, TG200
    SELECT coalesce(array_agg(t ORDER BY o), '{}') INTO v_tables
      FROM unnest(ARRAY[v_class.cellprotable, v_class.otherprotable]) WITH ORDINALITY AS u(t, o)
     WHERE t IS NOT NULL
       AND to_regclass(tgsis.chunk_relation(format('%I.%I', v_class.schemaname, t), '_shape')) IS NOT NULL
       AND to_regclass(tgsis.chunk_relation(format('%I.%I', v_class.schemaname, t), '_chunk')) IS NOT NULL;
    IF cardinality(v_tables) = 0 THEN
        RAISE EXCEPTION 'the properties of feature class % are not stored in chunks', coalesce(quote_literal(p_class), 'NULL')
            USING ERRCODE = 'TG200', DETAIL = 'Only what tgsis.store_class_in_chunks stored goes back to rows.';
    END IF;
    -- refused while another session's snapshot predates this transaction: it would read the row table EMPTY
    PERFORM tgsis.older_snapshots_check(format('tgsis.store_class_in_rows(%L)', p_class));
    IF EXISTS (SELECT FROM tgsis.versioned_tables t WHERE t.schemaname = v_class.schemaname AND t.tablename = ANY (v_tables)) THEN
        -- the versions' sets stay as they are until the switch is done (as tgsis.chunks_to_rows holds them); the
        -- conflicts' marks fingerprint the stored versions, which the switch changes without changing what any
        -- version sees: read before, renewed after (tgsis.renew_conflict_marks)
        PERFORM FROM tgsis.versions v ORDER BY v.versionid FOR SHARE;
        v_marks := tgsis.conflict_marks();
    END IF;
    -- both chunk tables locked before either moves; a DBA's index on either would go with it: refused by name (TG202)
    FOREACH v_tab IN ARRAY v_tables LOOP
        EXECUTE format('LOCK TABLE %s IN SHARE ROW EXCLUSIVE MODE',
                       tgsis.chunk_relation(format('%I.%I', v_class.schemaname, v_tab), '_chunk'));
        PERFORM tgsis.unkept_indexes_check(tgsis.chunk_relation(format('%I.%I', v_class.schemaname, v_tab), '_chunk')::regclass,
                                           true, format('tgsis.store_class_in_rows(%L)', p_class));
    END LOOP;
    FOREACH v_tab IN ARRAY v_tables LOOP
        v_name := format('%I.%I', v_class.schemaname, v_tab);
        v_shape := to_regclass(tgsis.chunk_relation(v_name, '_shape'));
        v_versioned := NULL;
        SELECT * INTO v_versioned FROM tgsis.versioned_tables t
         WHERE t.schemaname = v_class.schemaname AND t.tablename = v_tab;
        v_face := v_name::regclass;
        EXECUTE format('ALTER VIEW %s RENAME TO %I', v_face, v_tab || '_face');
        EXECUTE format('CREATE TABLE %s (LIKE %s INCLUDING CONSTRAINTS INCLUDING COMMENTS)', v_name, v_shape);
        EXECUTE format('ALTER TABLE %s DROP CONSTRAINT %I', v_name, v_tab || '_shape_holds_no_rows');
        FOR v_c IN SELECT con.conname, pg_get_constraintdef(con.oid) AS def FROM pg_constraint con
                    WHERE con.conrelid = v_shape AND con.contype = 'p' LOOP
            EXECUTE format('ALTER TABLE %s ADD CONSTRAINT %I %s', v_name, coalesce(v_versioned.pkeyname, v_tab || '_pkey'), v_c.def);
        END LOOP;
        PERFORM tgsis.move_row_indexes(v_shape, v_name::regclass);  -- the row table's own indexes, by name
        EXECUTE format('COMMENT ON TABLE %s IS %L', v_name,
                       CASE WHEN v_versioned.tablename IS NOT NULL THEN v_versioned.tablecomment  -- the table's own, before versioning
                            ELSE split_part(obj_description(v_face, 'pg_class'), ', stored in chunks (', 1) END);
        PERFORM tgsis.copy_relation_rights(v_face, v_name::regclass);  -- the face's grants, grant options kept
        IF v_versioned.tablename IS NOT NULL THEN
            -- versioned again as tgsis.version_class_tables versions it (the empty table becomes <table>_ver behind the
            -- versioned view, with the face's grants), then registered with what the registration said before
            DELETE FROM tgsis.versioned_tables t WHERE t.schemaname = v_versioned.schemaname AND t.tablename = v_versioned.tablename;
            PERFORM tgsis.enable_versioning_rel(v_name::regclass, v_versioned.objectkeyfield, v_versioned.objectclass,
                                                v_versioned.iudorder, v_versioned.shortname);
            UPDATE tgsis.versioned_tables t
               SET tablecomment = v_versioned.tablecomment, identity_always = v_versioned.identity_always,
                   enabled_at = v_versioned.enabled_at, enabled_by = v_versioned.enabled_by
             WHERE t.schemaname = v_versioned.schemaname AND t.tablename = v_versioned.tablename;
        END IF;
        v_n := v_n + tgsis.chunks_to_rows(v_name);  -- verified (TG000: nothing changed)
        -- this transaction's tables of rows written through the face (tgsis.chunk_face_write) are of its row type;
        -- another session's exist only while its writing transaction is open (ON COMMIT DROP), and would block the
        -- DROP below by name (2BP01: nothing changed); a session idle after it wrote holds none
        EXECUTE format('DROP TABLE IF EXISTS %s, %s, %s, %s', tgsis.chunk_face_work(v_name, 'now'),
                       tgsis.chunk_face_work(v_name, 'queue'), tgsis.chunk_face_work(v_name, 'rows'), tgsis.chunk_face_work(v_name, 'dels'));
        EXECUTE format('DROP VIEW %s', v_face);
        EXECUTE format('DROP FUNCTION IF EXISTS %I.%I()', v_class.schemaname, v_tab || '_face_row');  -- (tgsis.create_chunk_face)
        EXECUTE format('DROP VIEW %s', tgsis.chunk_relation(v_name, '_chunk_rows'));
        EXECUTE format('DROP TABLE %s', tgsis.chunk_relation(v_name, '_chunk'));
        EXECUTE format('DROP TABLE %s', v_shape);
        IF v_versioned.tablename IS NOT NULL THEN
            EXECUTE format('ANALYZE %I.%I', v_class.schemaname, v_tab || '_ver');
        END IF;
    END LOOP;
    IF v_marks IS NOT NULL THEN
        PERFORM tgsis.renew_conflict_marks(v_marks);
    END IF;
    -- again last, and at COMMIT: a snapshot taken while the switch ran, or before its transaction commits, would
    -- read the new row table EMPTY as well
    PERFORM tgsis.older_snapshots_check(format('tgsis.store_class_in_rows(%L)', p_class));
    PERFORM tgsis.older_snapshots_at_commit(format('tgsis.store_class_in_rows(%L)', p_class));
    RETURN v_n;
END
$$;

REVOKE ALL ON FUNCTION tgsis.store_class_in_rows(text) FROM PUBLIC;
GRANT EXECUTE ON FUNCTION tgsis.store_class_in_rows(text) TO tgsis_admin;

COMMENT ON FUNCTION tgsis.store_class_in_rows(text) IS
    'store a class''s property tables as rows again after tgsis.store_class_in_chunks (tgsis_admin members): each table in chunks (cellprotable and, when in chunks, otherprotable, in one transaction) made from its kept row definition with the face''s grants, filled from the chunks and verified (tgsis.chunks_to_rows), the face, chunk view, chunk table and shape dropped; a versioned class versioned again (tgsis.enable_versioning_rel, its registrations kept) with every chunk version as row versions of <table>_ver, verified against every version''s and revision''s set, the conflicts'' marks renewed; TG200 when neither is in chunks; returns the rows written';
