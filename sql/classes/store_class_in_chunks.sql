-- tgsis.store_class_in_chunks(class): store a STATIC class's property table in chunks behind a face with today's name (opt-in, issue 40).
-- docs/storage.md, "Property chunks: the contract": <schema>.<class>_cellpros
-- becomes a view (the face, tgsis.create_chunk_face) with today's columns over
-- <schema>.<class>_cellpros_chunk, filled from the rows and verified value for
-- value (tgsis.rows_to_chunks: bits for doubles and reals) before the rows
-- go; the row definition is kept without rows as <class>_cellpros_shape.
-- Reads, INSERT, UPDATE and DELETE through the face work as on the table
-- (tgsis.chunk_face_write, with the class table's grants). Nothing default
-- changes: only a tgsis_admin calling this switches a class. Built so far for
-- classes whose tables are not versioned (p_versioned => false, or feature
-- versioning off): a versioned class is refused by name (TG300), and so is
-- tgsis.enable_feature_versioning while a class's properties are in chunks
-- (tgsis.version_class_tables); add_property, rename_property and
-- drop_property convert the table back to rows and to chunks again around the
-- change (tgsis.alter_class_table); drop_feature_class drops the chunk table
-- with the class. The Python upload and download move whole chunks
-- (tgsis.write_property_chunks, src/tgsis/db/_property_chunks.py). tgsis.store_class_in_rows goes back.
-- Vector properties have no chunk form yet (TG100, tgsis.chunk_columns).
-- A table with row-level security, policies, a user's trigger, or a view or
-- foreign key over it is refused by name (TG202): a view can carry none of
-- them, and dropping the rows would lose them without an error.
-- SECURITY DEFINER: the class's tables belong to tgsis's owner. Returns the
-- chunk versions written.
CREATE FUNCTION tgsis.store_class_in_chunks(p_class text)
RETURNS bigint
LANGUAGE plpgsql
VOLATILE
SECURITY DEFINER
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_class tgsis.catalog;
    v_name  text;      -- the property table as the chunk layer names it (tgsis.chunk_registry)
    v_table regclass;
    v_users text;
    v_shape text;
    v_pkey  text;
    v_keys  text;
    v_n     bigint;
BEGIN
    v_class := tgsis.class_for_change(p_class, 'store in chunks the');  -- TG002 (not a tgsis_admin), TG200
    v_name := format('%I.%I', v_class.schemaname, v_class.cellprotable);
    IF v_class.timemodel <> 'STATIC' THEN
        RAISE EXCEPTION 'the properties of feature class % cannot be stored in chunks yet: it is of time model %', p_class,
                        v_class.timemodel
            USING ERRCODE = 'TG100',
                  DETAIL = 'Property chunks are built for STATIC classes (model 1); temporal classes keep their properties as rows.';
    END IF;
    IF to_regclass(tgsis.chunk_relation(v_name, '_chunk')) IS NOT NULL THEN
        RAISE EXCEPTION 'the properties of feature class % are stored in chunks already', p_class
            USING ERRCODE = 'TG201', DETAIL = format('Their chunk table is %s.', tgsis.chunk_relation(v_name, '_chunk'));
    END IF;
    IF EXISTS (SELECT FROM tgsis.versioned_tables t WHERE t.schemaname = v_class.schemaname AND t.tablename = v_class.cellprotable) THEN
        RAISE EXCEPTION 'the properties of feature class % cannot be stored in chunks yet: the class is versioned', p_class
            USING ERRCODE = 'TG300',
                  DETAIL = 'Property chunks are built for classes whose tables are not versioned (registered with p_versioned => false, '
                           'or while feature versioning is off); the merges and the bulk paths of versioned classes read rows.';
    END IF;
    v_shape := v_class.cellprotable || '_shape';
    IF to_regclass(format('%I.%I', v_class.schemaname, v_shape)) IS NOT NULL
       OR to_regclass(format('%I.%I', v_class.schemaname, v_class.cellprotable || '_face')) IS NOT NULL
       OR octet_length(v_class.cellprotable || '_chunk_rows') > 63 THEN
        RAISE EXCEPTION 'the names %, % or % are taken or too long in schema %', v_shape, v_class.cellprotable || '_face',
                        v_class.cellprotable || '_chunk_rows', v_class.schemaname
            USING ERRCODE = 'TG201', DETAIL = 'Storing the properties in chunks needs these names for the row definition, the face and the chunk view.';
    END IF;
    v_table := format('%I.%I', v_class.schemaname, v_class.cellprotable)::regclass;
    EXECUTE format('LOCK TABLE %s IN SHARE ROW EXCLUSIVE MODE', v_table);
    -- what the table carries that a view cannot, or that its drop would take along: row-level security and its
    -- policies (the rows a role may see), a user's trigger, a view or foreign key over it; dropped with the rows,
    -- they would be lost without an error, so the switch is refused by name
    v_users := concat_ws(', ',
        CASE WHEN (SELECT c.relrowsecurity FROM pg_class c WHERE c.oid = v_table) THEN 'row-level security' END,
        (SELECT string_agg(format('policy %I', p.polname), ', ' ORDER BY p.polname) FROM pg_policy p WHERE p.polrelid = v_table),
        tgsis.relation_users(v_table, '{}', '{}'));
    IF v_users <> '' THEN
        RAISE EXCEPTION 'the properties of feature class % cannot be stored in chunks: % carries what its face could not',
                        p_class, v_table
            USING ERRCODE = 'TG202', DETAIL = 'used by or set on it: ' || v_users,
                  HINT = 'drop them (and the row-level security), store the class in chunks, then create what a view allows again';
    END IF;

    -- 1. the chunks, verified against the rows (TG100 for a property the layout has no form for)
    PERFORM tgsis.create_chunk_table(v_name);
    PERFORM tgsis.create_chunk_view(v_name);
    v_n := tgsis.rows_to_chunks(v_name);

    -- 2. the row definition, without rows
    SELECT con.conname, string_agg(quote_ident(a.attname), ', ' ORDER BY k.ord) INTO v_pkey, v_keys
      FROM pg_constraint con
     CROSS JOIN LATERAL unnest(con.conkey) WITH ORDINALITY AS k(attnum, ord)
      JOIN pg_attribute a ON a.attrelid = con.conrelid AND a.attnum = k.attnum
     WHERE con.conrelid = v_table AND con.contype = 'p'
     GROUP BY con.conname;
    EXECUTE format('CREATE TABLE %I.%I (LIKE %s INCLUDING CONSTRAINTS INCLUDING COMMENTS)', v_class.schemaname, v_shape, v_table);
    EXECUTE format('ALTER TABLE %I.%I ADD CONSTRAINT %I PRIMARY KEY (%s)', v_class.schemaname, v_shape, v_shape || '_pkey', v_keys);
    EXECUTE format('ALTER TABLE %I.%I ADD CONSTRAINT %I CHECK (false)', v_class.schemaname, v_shape,
                   v_class.cellprotable || '_shape_holds_no_rows');
    EXECUTE format('COMMENT ON TABLE %I.%I IS %L', v_class.schemaname, v_shape, obj_description(v_table, 'pg_class'));

    -- 3. the face takes the name (with the table's grants); the rows go
    PERFORM tgsis.create_chunk_face(v_name, v_class.cellprotable || '_face');
    EXECUTE format('COMMENT ON TABLE %I.%I IS %L', v_class.schemaname, v_shape,
                   format('the row definition of %s (columns, key %s, constraints, comments), kept without rows since its properties '
                          'are stored in chunks (%s behind the face %s: tgsis.store_class_in_chunks)',
                          v_name, v_pkey, tgsis.chunk_relation(v_name, '_chunk'), v_name));
    EXECUTE format('DROP TABLE %s', v_table);
    EXECUTE format('ALTER VIEW %I.%I RENAME TO %I', v_class.schemaname, v_class.cellprotable || '_face', v_class.cellprotable);
    RETURN v_n;
END
$$;

REVOKE ALL ON FUNCTION tgsis.store_class_in_chunks(text) FROM PUBLIC;
GRANT EXECUTE ON FUNCTION tgsis.store_class_in_chunks(text) TO tgsis_admin;

COMMENT ON FUNCTION tgsis.store_class_in_chunks(text) IS
    'store the property table <schema>.<class>_cellpros of a STATIC class not versioned in chunks (opt-in, tgsis_admin members): <class>_cellpros_chunk filled from the rows and verified (tgsis.rows_to_chunks), the row definition kept as <class>_cellpros_shape, <class>_cellpros made the face over the chunks (today''s columns and grants; INSERT, UPDATE, DELETE through it); TG300 for a versioned class, TG100 for a temporal one or a vector property, TG201 when stored in chunks already, TG202 when the table has row-level security, policies, a user''s trigger or a view or foreign key over it; returns the chunk versions written; tgsis.store_class_in_rows goes back';
