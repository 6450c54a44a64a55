-- tgsis.store_class_in_chunks(class): store a class's property tables (models 1 to 3) in chunks behind faces with today's names (issue 40).
-- docs/storage.md, "Property chunks: the contract": <schema>.<class>_cellpros
-- (and the class's table of properties of the other alignment, otherprotable,
-- e.g. <class>_simplexpros: both in one transaction, every refusal of either
-- table raised before anything moves; a table in chunks already is left as
-- it is, TG201 when both are; a table without a property column stays rows
-- when the other has one to switch) becomes a view (the face, tgsis.create_chunk_face) with today's columns over
-- <schema>.<class>_cellpros_chunk, filled from the rows and verified value for
-- value (tgsis.rows_to_chunks: bits for doubles and reals) before the rows
-- go; the row definition is kept without rows as <class>_cellpros_shape.
-- Reads, INSERT, UPDATE and DELETE through the face work as on the table
-- (tgsis.chunk_face_write, with the class table's grants). Nothing default
-- changes: only a tgsis_admin calling this switches a class. A versioned
-- class (its tables registered in tgsis.versioned_tables) switches with its
-- history: every chunk version written from the row versions of <table>_ver
-- and verified against every version's and revision's set, the versioned
-- view and its <table>_ver, queue, write function and runner dropped, the
-- registration kept (tgsis.storage_table then names the chunk table, which
-- is guarded as <table>_ver was: tgsis.guard_chunk_storage), the conflicts'
-- marks renewed (solved conflicts stay solved), as tgsis.store_in_chunks does
-- for a model table. tgsis.enable_feature_versioning versions a class whose
-- properties are in chunks (tgsis.version_class_tables). add_property,
-- rename_property and drop_property alter the chunk table in place, every
-- chunk version, versioned or not (tgsis.alter_class_table,
-- tgsis.alter_chunk_table);
-- drop_feature_class drops the chunk table with the class. The Python upload
-- and download of an unversioned class move whole chunks
-- (tgsis.write_property_chunks, src/tgsis/db/_property_chunks.py).
-- tgsis.store_class_in_rows goes back, a versioned class with its history.
-- A vector property (size k) is a two-dimensional array, slots x k (plan K,
-- area V), which the client codec encodes too (plan L: the Python upload,
-- download and check-in swap move its chunks whole).
-- A table with row-level security, policies, a user's trigger, or a view or
-- foreign key over it is refused by name (TG202): a view can carry none of
-- them, and dropping the rows would lose them without an error.
-- SECURITY DEFINER: the class's tables belong to tgsis's owner. Returns the
-- chunk versions written. A temporal class (INSTANTS: <class>_cellpros keyed
-- _geoid, _times, _idx; EVOLVING: _geoid, _timem, _timet, _idx) is switched
-- the same way, its chunks keyed by its instants too; the
-- G-map models' classes are refused (TG100).
CREATE FUNCTION tgsis.store_class_in_chunks(p_class text)
RETURNS bigint
LANGUAGE plpgsql
VOLATILE
SECURITY DEFINER
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_class  tgsis.catalog;
    v_tables text[];   -- the property tables still rows: cellprotable, then otherprotable
    v_tab    text;
    v_name   text;     -- a property table as the chunk layer names it (tgsis.chunk_registry)
    v_table  regclass;
    v_users  text;
    v_shape  text;
    v_pkey   text;
    v_keys   text;
    v_n      bigint := 0;
    v_versioned tgsis.versioned_tables;
    v_storage   regclass;
    v_marks     jsonb;
    v_proc      text;
BEGIN
    v_class := tgsis.class_for_change(p_class, 'store in chunks the');  -- TG002 (not a tgsis_admin), TG200
    IF v_class.timemodel NOT IN ('STATIC', 'INSTANTS', 'EVOLVING') THEN
        RAISE EXCEPTION 'the properties of feature class % cannot be stored in chunks yet: it is of time model %', p_class,
                        v_class.timemodel
            USING ERRCODE = 'TG100',
                  DETAIL = 'Property chunks are built for STATIC, INSTANTS and EVOLVING classes (models 1 to 3); the G-map models keep their properties as rows.';
    END IF;
    -- both property tables (the class's alignment and, when it has one, the other's); one already in chunks (switched
    -- by a tgsis that knew only cellprotable) is left as it is;
    -- a table without a property column (all of its alignment dropped, or none of the class's alignment) has
    -- nothing a chunk would hold: it stays rows
    SELECT coalesce(array_agg(t ORDER BY o), '{}') INTO v_tables
      FROM unnest(ARRAY[v_class.cellprotable, v_class.otherprotable]) WITH ORDINALITY AS u(t, o)
     WHERE t IS NOT NULL AND to_regclass(tgsis.chunk_relation(format('%I.%I', v_class.schemaname, t), '_chunk')) IS NULL
       AND EXISTS (SELECT FROM pg_attribute a
                    WHERE a.attrelid = tgsis.storage_table(v_class.schemaname, t)::regclass AND a.attnum > 0
                      AND NOT a.attisdropped
                      AND a.attname NOT IN ('_geoid', '_idx', '_times', '_timem', '_timet', 'revision', 'lastrevs', 'revclosed'));
    IF cardinality(v_tables) = 0
       AND to_regclass(tgsis.chunk_relation(format('%I.%I', v_class.schemaname, v_class.cellprotable), '_chunk')) IS NULL
       AND (v_class.otherprotable IS NULL
            OR to_regclass(tgsis.chunk_relation(format('%I.%I', v_class.schemaname, v_class.otherprotable), '_chunk')) IS NULL) THEN
        v_tables := ARRAY[v_class.cellprotable];  -- no property at all: tgsis.chunk_columns refuses it by name (TG100)
    END IF;
    IF cardinality(v_tables) = 0 THEN
        RAISE EXCEPTION 'the properties of feature class % are stored in chunks already', p_class
            USING ERRCODE = 'TG201',
                  DETAIL = (SELECT format('Their chunk table%s %s.', CASE WHEN count(*) = 1 THEN ' is' ELSE 's are' END,
                                          string_agg(c, ' and ' ORDER BY o))
                              FROM unnest(ARRAY[v_class.cellprotable, v_class.otherprotable]) WITH ORDINALITY AS u(t, o),
                                   LATERAL tgsis.chunk_relation(format('%I.%I', v_class.schemaname, t), '_chunk') AS c
                             WHERE t IS NOT NULL AND to_regclass(c) IS NOT NULL);
    END IF;

    -- the refusals, for every table before anything moves
    FOREACH v_tab IN ARRAY v_tables LOOP
        SELECT * INTO v_versioned FROM tgsis.versioned_tables t
         WHERE t.schemaname = v_class.schemaname AND t.tablename = v_tab;
        v_shape := v_tab || '_shape';
        IF to_regclass(format('%I.%I', v_class.schemaname, v_shape)) IS NOT NULL
           OR to_regclass(format('%I.%I', v_class.schemaname, v_tab || '_face')) IS NOT NULL
           OR octet_length(v_tab || '_chunk_rows') > 63 THEN
            RAISE EXCEPTION 'the names %, % or % are taken or too long in schema %', v_shape, v_tab || '_face',
                            v_tab || '_chunk_rows', v_class.schemaname
                USING ERRCODE = 'TG201', DETAIL = 'Storing the properties in chunks needs these names for the row definition, the face and the chunk view.';
        END IF;
        v_table := format('%I.%I', v_class.schemaname, v_tab)::regclass;
        v_storage := tgsis.storage_table(v_class.schemaname, v_tab)::regclass;  -- the table, or its <table>_ver
        -- a DBA's index on the row versions' revision columns cannot be kept: refused by name (TG202)
        PERFORM tgsis.unkept_indexes_check(v_storage, false, format('tgsis.store_class_in_chunks(%L)', p_class));
        EXECUTE format('LOCK TABLE %s IN SHARE ROW EXCLUSIVE MODE', v_storage);
        -- what the table carries that a view cannot, or that its drop would take along: row-level security and its
        -- policies (the rows a role may see), a user's trigger, a view or foreign key over it; dropped with the rows,
        -- they would be lost without an error, so the switch is refused by name
        v_users := concat_ws(', ',
            CASE WHEN (SELECT c.relrowsecurity FROM pg_class c WHERE c.oid = v_table) THEN 'row-level security' END,
            (SELECT string_agg(format('policy %I', p.polname), ', ' ORDER BY p.polname) FROM pg_policy p WHERE p.polrelid = v_table),
            CASE WHEN v_versioned.tablename IS NULL THEN tgsis.relation_users(v_table, '{}', '{}')
                 -- versioned: the view and its <table>_ver, less what versioning made (the view's own rule and
                 -- triggers, the storage's triggers)
                 ELSE concat_ws(', ',
                     CASE WHEN (SELECT c.relrowsecurity FROM pg_class c WHERE c.oid = v_storage) THEN format('row-level security on %s', v_storage) END,
                     (SELECT string_agg(format('policy %I on %s', p.polname, v_storage), ', ' ORDER BY p.polname)
                        FROM pg_policy p WHERE p.polrelid = v_storage),
                     tgsis.relation_users(v_table, ARRAY[v_table], '{tgsis_versioning,tgsis_versioning_flush,tgsis_versioning_rights}'),
                     tgsis.relation_users(v_storage, ARRAY[v_table], '{tgsis_storage_write,tgsis_storage_rows,tgsis_storage_changes}'))
            END);
        IF v_users <> '' THEN
            RAISE EXCEPTION 'the properties of feature class % cannot be stored in chunks: % carries what its face could not',
                            p_class, v_table
                USING ERRCODE = 'TG202', DETAIL = 'used by or set on it: ' || v_users,
                      HINT = 'drop them (and the row-level security), store the class in chunks, then create what a view allows again';
        END IF;
    END LOOP;

    -- the conflicts' marks fingerprint the stored versions, which the switch changes without changing what any
    -- version sees: read before, renewed after (tgsis.renew_conflict_marks), solved conflicts stay solved
    IF EXISTS (SELECT FROM tgsis.versioned_tables t WHERE t.schemaname = v_class.schemaname AND t.tablename = ANY (v_tables)) THEN
        v_marks := tgsis.conflict_marks();
    END IF;

    FOREACH v_tab IN ARRAY v_tables LOOP
        v_name := format('%I.%I', v_class.schemaname, v_tab);
        v_versioned := NULL;
        SELECT * INTO v_versioned FROM tgsis.versioned_tables t
         WHERE t.schemaname = v_class.schemaname AND t.tablename = v_tab;
        v_shape := v_tab || '_shape';
        v_table := v_name::regclass;
        v_storage := tgsis.storage_table(v_class.schemaname, v_tab)::regclass;

        -- 1. the chunks, verified against the rows (every version's and revision's set when versioned; TG100 for a
        -- property the layout has no form for)
        PERFORM tgsis.create_chunk_table(v_name);
        PERFORM tgsis.create_chunk_view(v_name);
        v_n := v_n + tgsis.rows_to_chunks(v_name);

        -- 2. the row definition, without rows (of a versioned table: its storage without the versioning columns, the
        -- key as registered)
        IF v_versioned.tablename IS NOT NULL THEN
            v_pkey := v_versioned.pkeyname;
            v_keys := (SELECT string_agg(quote_ident(k), ', ' ORDER BY o) FROM unnest(v_versioned.keycolumns) WITH ORDINALITY AS u(k, o));
        ELSE
            SELECT con.conname, string_agg(quote_ident(a.attname), ', ' ORDER BY k.ord) INTO v_pkey, v_keys
              FROM pg_constraint con
             CROSS JOIN LATERAL unnest(con.conkey) WITH ORDINALITY AS k(attnum, ord)
              JOIN pg_attribute a ON a.attrelid = con.conrelid AND a.attnum = k.attnum
             WHERE con.conrelid = v_table AND con.contype = 'p'
             GROUP BY con.conname;
        END IF;
        EXECUTE format('CREATE TABLE %I.%I (LIKE %s INCLUDING CONSTRAINTS INCLUDING COMMENTS)', v_class.schemaname, v_shape, v_storage);
        IF v_versioned.tablename IS NOT NULL THEN
            EXECUTE format('ALTER TABLE %I.%I DROP COLUMN revision, DROP COLUMN lastrevs, DROP COLUMN revclosed', v_class.schemaname, v_shape);
        END IF;
        EXECUTE format('ALTER TABLE %I.%I ADD CONSTRAINT %I PRIMARY KEY (%s)', v_class.schemaname, v_shape, v_shape || '_pkey', v_keys);
        EXECUTE format('ALTER TABLE %I.%I ADD CONSTRAINT %I CHECK (false)', v_class.schemaname, v_shape,
                       v_tab || '_shape_holds_no_rows');
        EXECUTE format('COMMENT ON TABLE %I.%I IS %L', v_class.schemaname, v_shape,
                       coalesce(v_versioned.tablecomment, obj_description(v_table, 'pg_class')));

        -- 3. the face takes the name (with the table's grants); the rows go
        PERFORM tgsis.create_chunk_face(v_name, v_tab || '_face');
        EXECUTE format('COMMENT ON TABLE %I.%I IS %L', v_class.schemaname, v_shape,
                       format('the row definition of %s (columns, key %s, constraints, comments), kept without rows since its properties '
                              'are stored in chunks (%s behind the face %s: tgsis.store_class_in_chunks)',
                              v_name, v_pkey, tgsis.chunk_relation(v_name, '_chunk'), v_name));
        IF v_versioned.tablename IS NOT NULL THEN
            -- the versioned view and what serves it go; the registration stays (the chunk table is its storage)
            EXECUTE format('DROP VIEW %s', v_table);
            EXECUTE format('DROP FUNCTION %I.%I()', v_class.schemaname, v_tab || '_ver_write');
            EXECUTE format('DROP TABLE %I.%I', v_class.schemaname, v_tab || '_ver_queue');
            FOR v_proc IN SELECT p.oid::regprocedure::text FROM pg_proc p
                           WHERE p.pronamespace = (SELECT n.oid FROM pg_namespace n WHERE n.nspname = v_class.schemaname) AND p.proname = v_tab || '_ver_run' LOOP
                EXECUTE format('DROP FUNCTION %s', v_proc);
            END LOOP;
        END IF;
        -- the row table's own secondary indexes kept on the row definition, by name (the way back makes them again)
        PERFORM tgsis.move_row_indexes(v_storage, format('%I.%I', v_class.schemaname, v_shape)::regclass);
        EXECUTE format('DROP TABLE %s', v_storage);
        EXECUTE format('ALTER VIEW %I.%I RENAME TO %I', v_class.schemaname, v_tab || '_face', v_tab);
        IF v_versioned.tablename IS NOT NULL THEN
            PERFORM tgsis.guard_chunk_storage(v_name);  -- the rights, labels and notes <table>_ver's triggers kept
            EXECUTE format('ANALYZE %s', tgsis.chunk_relation(v_name, '_chunk'));
        END IF;
    END LOOP;
    IF v_marks IS NOT NULL THEN
        PERFORM tgsis.renew_conflict_marks(v_marks);
    END IF;
    RETURN v_n;
END
$$;

REVOKE ALL ON FUNCTION tgsis.store_class_in_chunks(text) FROM PUBLIC;
GRANT EXECUTE ON FUNCTION tgsis.store_class_in_chunks(text) TO tgsis_admin;

COMMENT ON FUNCTION tgsis.store_class_in_chunks(text) IS
    'store the property tables of a STATIC, INSTANTS or EVOLVING class in chunks (tgsis_admin members; a temporal class''s chunks keyed by its instants too), versioned or not: <schema>.<class>_cellpros and, when the class has one, its table of properties of the other alignment (otherprotable), in one transaction, every refusal checked before anything moves; each as <table>_chunk filled from the rows (every row version when versioned) and verified (tgsis.rows_to_chunks), the row definition kept as <table>_shape, <table> made the face over the chunks (today''s columns and grants; INSERT, UPDATE, DELETE through it), a versioned class keeping its registrations with the chunk tables as their storage (guarded as <table>_ver was); TG100 for a class of a G-map model, TG201 when stored in chunks already, TG202 when a table has row-level security, policies, a user''s trigger or a view or foreign key over it; returns the chunk versions written; tgsis.store_class_in_rows goes back';
