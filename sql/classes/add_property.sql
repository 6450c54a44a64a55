-- tgsis.add_property(class, kind, property, default): give a feature class one more property, in every version.
-- p_kind: 'feature' (a column of the feature table), 'cell' (a vertex or
-- cell property: a column of cellprotable, or of otherprotable for one
-- aligned otherwise than the class) or 'instant' (a per-instant property of a
-- temporal class, a column of protablename). p_property is one item as
-- register_feature_class takes them ({"name": ..., "type": ..., "size": k,
-- "alignment": ...} or [name, type, k]), checked the same way.
-- Rows already stored (every row version of every version) get p_default:
-- feature and per-instant properties may be NULL, vertex and cell properties
-- may not (they travel as numpy arrays), so a class with rows needs a
-- default for them; a vector property gets it in each component. New rows
-- give their own values, as at registration (the default is not kept).
-- A class registered without vertex or cell properties of that alignment has
-- no rows in the table yet: every stored feature (and collection member
-- that has all the class's properties) gets one per vertex or cell holding
-- the default, in every version and revision (tgsis.insert_property_rows),
-- or the change is refused with nothing done (no default; a model keyed by
-- time or cell level; a table whose other properties lack those rows too,
-- which tgsis.fill_property_rows repairs first). The feature table is locked
-- against writers meanwhile, so an upload in flight is counted or waits.
-- A NOTICE says how many features and rows got the default.
-- The first vertex or cell property of a STATIC class's table puts the class
-- in chunks when model 1 is in chunks and tgsis.storage is not rows
-- (tgsis.chunk_class_by_default), as registering it with that property would
-- have: the rows just given the default move to chunks, verified.
-- Runs as tgsis's owner (SECURITY DEFINER), who owns the class's tables, for
-- members of tgsis_admin, like register_feature_class.
CREATE FUNCTION tgsis.add_property(p_class text, p_kind text, p_property jsonb, p_default text DEFAULT NULL)
RETURNS tgsis.catalog
LANGUAGE plpgsql
VOLATILE
SECURITY DEFINER
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_class    tgsis.catalog := tgsis.class_for_change(p_class, 'add');
    v_prop     record;
    v_align    text;
    v_table    text;
    v_list     jsonb;
    v_item     jsonb;
    v_type     text;
    v_notnull  boolean;
    v_value    text;
    v_rows     boolean;
    v_missing  bigint[] := '{}';
    v_made     record;
    v_geoms    bigint;
    v_count    bigint;
    v_what     text;
    v_row      tgsis.catalog;
    v_check    text := '';  -- a vector's CHECK named as on the row storage when the table is in chunks (below)
    v_n1       text;
    v_n2       text;
    v_b1       integer;   -- their lengths in bytes, as PostgreSQL shortens them
    v_b2       integer;
    v_label    text;
    v_pass     integer;
    v_first    boolean;   -- a vertex or cell property, the first of its table
BEGIN
    IF p_kind IS NULL OR p_kind NOT IN ('feature', 'cell', 'instant') THEN
        RAISE EXCEPTION 'property kind % must be feature, cell or instant', coalesce(quote_literal(p_kind), 'NULL')
            USING ERRCODE = 'TG100',
                  HINT = 'feature: a value per feature; cell: per vertex or cell; instant: per feature and instant';
    END IF;
    IF p_kind = 'instant' AND v_class.protablename IS NULL THEN
        RAISE EXCEPTION 'static feature class % has no per-instant properties', p_class
            USING ERRCODE = 'TG100', HINT = 'add a feature property (p_kind => ''feature'') instead';
    END IF;
    IF p_property IS NULL OR jsonb_typeof(p_property) NOT IN ('object', 'array') THEN
        RAISE EXCEPTION 'property % must be {"name": ..., "type": ...} or [name, type]', coalesce(p_property::text, 'NULL')
            USING ERRCODE = 'TG103';
    END IF;
    SELECT * INTO v_prop FROM tgsis.property_columns(jsonb_build_array(p_property), p_kind = 'cell',
                                                     CASE p_kind WHEN 'cell' THEN lower(v_class.proalignment)
                                                                 WHEN 'instant' THEN 'per-instant' ELSE 'feature' END);
    IF v_prop.name IN ('revision', 'lastrevs', 'revclosed')
       OR (p_kind = 'feature' AND v_prop.name IN ('geoname', 'geotype', 'nvrtx', 'ncell', 'bbox', 'created_at'))
       OR (p_kind = 'cell' AND v_prop.name = 'part') THEN
        RAISE EXCEPTION '% property name % is taken by tgsis', p_kind, quote_literal(v_prop.name)
            USING ERRCODE = 'TG101',
                  DETAIL = CASE WHEN v_prop.name = 'part'
                                THEN 'A cell property "part" holds the parts of features stored in tgsis.part otherwise; only a class registered with it stores them there.'
                                WHEN v_prop.name IN ('revision', 'lastrevs', 'revclosed')
                                THEN 'Versioning adds the columns revision, lastrevs and revclosed.'
                                ELSE format('The class view %s has a column of that name from tgsis.geometry.', v_class.viewname) END,
                  HINT = 'choose another name';
    END IF;
    v_list := CASE p_kind WHEN 'feature' THEN v_class.feature_properties WHEN 'cell' THEN v_class.cell_properties
                          ELSE v_class.instant_properties END;
    IF EXISTS (SELECT FROM jsonb_array_elements(v_list) p WHERE p ->> 'name' = v_prop.name) THEN
        RAISE EXCEPTION 'feature class % has a % property % already', p_class, p_kind, quote_literal(v_prop.name)
            USING ERRCODE = 'TG201', HINT = 'choose another name, or rename or drop the existing property first';
    END IF;
    v_table := CASE p_kind WHEN 'feature' THEN v_class.featuretable WHEN 'instant' THEN v_class.protablename
                           ELSE v_class.cellprotable END;
    v_item := jsonb_build_object('name', v_prop.name, 'type', v_prop.typename);
    v_what := CASE p_kind WHEN 'feature' THEN 'per-feature property' WHEN 'instant' THEN 'per-instant feature property'
                          ELSE lower(v_class.proalignment) || ' property' END;
    IF p_kind = 'cell' THEN
        v_align := coalesce(v_prop.alignment, v_class.proalignment);
        IF v_class.protablename IS NOT NULL AND (v_prop.size > 1 OR v_align <> v_class.proalignment) THEN
            RAISE EXCEPTION 'temporal feature class % takes no vector properties nor properties of another alignment', p_class
                USING ERRCODE = 'TG103', HINT = 'give one scalar property per component, all of the class''s alignment';
        END IF;
        IF v_align <> v_class.proalignment THEN
            IF v_class.otherprotable IS NULL THEN
                RAISE EXCEPTION 'feature class % has no table for % properties', p_class, lower(v_align)
                    USING ERRCODE = 'TG103',
                          DETAIL = format('Its vertex or cell properties are all per %s; properties of the other alignment go to a table of their own, made at registration.',
                                          lower(v_class.proalignment)),
                          HINT = 'register the class with a property of that alignment, or add a property of the class''s alignment';
            END IF;
            v_table := v_class.otherprotable;
            v_item := v_item || jsonb_build_object('alignment', v_align);
            v_what := lower(v_align) || ' property';
        END IF;
        IF v_prop.size > 1 THEN
            v_item := v_item || jsonb_build_object('size', v_prop.size);
        END IF;
    END IF;
    v_first := p_kind = 'cell'
               AND NOT EXISTS (SELECT FROM jsonb_array_elements(v_class.cell_properties) p
                                WHERE coalesce(p ->> 'alignment', v_class.proalignment) = coalesce(v_align, v_class.proalignment));
    v_type := v_prop.typename || CASE WHEN v_prop.size > 1 THEN '[]' ELSE '' END;
    -- as at registration: vertex and cell properties are NOT NULL but in collections (members lack some)
    v_notnull := p_kind = 'cell' AND v_class.geotype <> 'GEOMETRYCOLLECTION';

    IF p_default IS NOT NULL THEN
        BEGIN
            EXECUTE format('SELECT %L::%s', p_default, v_prop.typename) INTO v_value;
        EXCEPTION WHEN data_exception THEN
            RAISE EXCEPTION 'default % of property % is not a valid %', quote_literal(p_default), quote_literal(v_prop.name),
                    v_prop.typename
                USING ERRCODE = 'TG103', DETAIL = SQLERRM, HINT = format('give a value PostgreSQL reads as %s', v_prop.typename);
        END;
    END IF;
    EXECUTE format('SELECT EXISTS (SELECT FROM %s)', tgsis.storage_table(v_class.schemaname, v_table)) INTO v_rows;
    IF p_kind = 'cell' THEN
        -- uploads in flight write the feature table first: they finish before this looks, or wait for the change
        EXECUTE format('LOCK TABLE %s IN SHARE ROW EXCLUSIVE MODE', tgsis.storage_table(v_class.schemaname, v_class.featuretable));
        v_missing := tgsis.property_rows_missing(v_class, v_table);
    END IF;
    IF cardinality(v_missing) > 0 THEN
        IF p_default IS NULL THEN
            RAISE EXCEPTION 'feature class % has % stored geometries without rows in %, which need a value of the new % property %',
                    p_class, cardinality(v_missing), v_table, lower(coalesce(v_align, '')), quote_literal(v_prop.name)
                USING ERRCODE = 'TG103',
                      DETAIL = 'The class had no vertex or cell property of that alignment: its features have no rows in that table yet, and each vertex or cell gets one with the default.',
                      HINT = 'give p_default, e.g. ''0''';
        END IF;
        IF EXISTS (SELECT FROM jsonb_array_elements(v_class.cell_properties) p
                    WHERE coalesce(p ->> 'alignment', v_class.proalignment) = coalesce(v_align, v_class.proalignment)) THEN
            RAISE EXCEPTION 'feature class % has % stored geometries without rows in %, though it has % properties already',
                    p_class, cardinality(v_missing), v_table, lower(coalesce(v_align, v_class.proalignment))
                USING ERRCODE = 'TG103',
                      DETAIL = 'Their features cannot be read until each vertex or cell has a row with a value of every property of that table.',
                      HINT = format('give them rows first: SELECT * FROM tgsis.fill_property_rows(%L, ''{"property": value}'')', p_class);
        END IF;
    END IF;
    IF v_notnull AND p_default IS NULL AND v_rows THEN
        RAISE EXCEPTION 'feature class % has stored rows in %, which need a value of the new % property %', p_class,
                v_table, lower(coalesce(v_align, '')), quote_literal(v_prop.name)
            USING ERRCODE = 'TG103',
                  DETAIL = 'Vertex and cell properties may not be NULL; the rows of every version get the default.',
                  HINT = 'give p_default, e.g. ''0''';
    END IF;

    -- a vector's CHECK: on a table in chunks it is added to <table>_shape, where PostgreSQL would name it
    -- <table>_shape_<column>_check; it gets the name the row storage (<table>, or <table>_ver when versioned) would
    -- give it, so that the writers of chunks name the same constraint as rows do (23514: tgsis.write_chunk_rows).
    -- PostgreSQL's rule (ChooseConstraintName, makeObjectName): the label "check", then "check1", "check2"... while
    -- a constraint of the schema holds the name (the shape keeps the row table's constraint names, so a name the
    -- rows would find taken is taken here too: a renamed vector's CHECK keeps its old name); both names shortened
    -- in bytes, the longer first, to 63 bytes with the label and the underscores, each then cut back to a whole
    -- character (pg_mbcliplen: a non-ASCII name at the limit)
    IF v_prop.size > 1 AND tgsis.stored_in_chunks(v_class.schemaname, v_table) THEN
        v_pass := 0;
        LOOP
            v_label := 'check' || CASE WHEN v_pass > 0 THEN v_pass::text ELSE '' END;
            v_n1 := v_table || CASE WHEN EXISTS (SELECT FROM tgsis.versioned_tables t
                                                  WHERE t.schemaname = v_class.schemaname AND t.tablename = v_table)
                                    THEN '_ver' ELSE '' END;
            v_n2 := v_prop.name;
            v_b1 := octet_length(v_n1);
            v_b2 := octet_length(v_n2);
            WHILE v_b1 + v_b2 > 63 - 2 - octet_length(v_label) LOOP
                IF v_b1 > v_b2 THEN
                    v_b1 := v_b1 - 1;
                ELSE
                    v_b2 := v_b2 - 1;
                END IF;
            END LOOP;
            WHILE octet_length(v_n1) > v_b1 LOOP
                v_n1 := left(v_n1, -1);
            END LOOP;
            WHILE octet_length(v_n2) > v_b2 LOOP
                v_n2 := left(v_n2, -1);
            END LOOP;
            EXIT WHEN NOT EXISTS (SELECT FROM pg_constraint con JOIN pg_namespace n ON n.oid = con.connamespace
                                   WHERE n.nspname = v_class.schemaname AND con.conname = v_n1 || '_' || v_n2 || '_' || v_label);
            v_pass := v_pass + 1;
        END LOOP;
        v_check := format(' CONSTRAINT %I', v_n1 || '_' || v_n2 || '_' || v_label);
    END IF;
    -- the rows stored get the default; new rows give their values, as in a class registered with the property
    PERFORM tgsis.alter_class_table(v_class, v_table, ARRAY[
        format('ADD COLUMN %I %s%s DEFAULT %s%s', v_prop.name, v_type, CASE WHEN v_notnull THEN ' NOT NULL' ELSE '' END,
               CASE WHEN p_default IS NULL THEN 'NULL'
                    WHEN v_prop.size > 1 THEN format('array_fill(%L::%s, ARRAY[%s])', p_default, v_prop.typename, v_prop.size)
                    ELSE format('%L::%s', p_default, v_prop.typename) END,
               CASE WHEN v_prop.size > 1
                    THEN v_check || format(' CHECK (array_ndims(%I) = 1 AND array_lower(%I, 1) = 1 AND cardinality(%I) = %s '
                                'AND array_position(%I, NULL) IS NULL)', v_prop.name, v_prop.name, v_prop.name, v_prop.size,
                                v_prop.name)
                    ELSE '' END),
        format('ALTER COLUMN %I DROP DEFAULT', v_prop.name)], jsonb_build_array(v_item), v_what);
    IF cardinality(v_missing) > 0 THEN
        SELECT * INTO v_made FROM tgsis.insert_property_rows(v_class, v_table, v_missing, ARRAY[v_prop.name], ARRAY[
            CASE WHEN v_prop.size > 1 THEN format('array_fill(%L::%s, ARRAY[%s])', p_default, v_prop.typename, v_prop.size)
                 ELSE format('%L::%s', p_default, v_prop.typename) END]);
    END IF;
    IF p_default IS NOT NULL THEN
        EXECUTE format('SELECT count(DISTINCT _geoid), count(*) FROM %I.%I', v_class.schemaname, v_table)
           INTO v_geoms, v_count;
        RAISE NOTICE 'new % % of feature class %: % in % row(s) of % stored geometries (as this version reads them; every version''s rows got it)',
            v_what, v_prop.name, p_class, p_default, v_count, v_geoms;
    END IF;
    UPDATE tgsis.catalog c SET feature_properties = CASE WHEN p_kind = 'feature' THEN c.feature_properties || v_item
                                                         ELSE c.feature_properties END,
                               cell_properties = CASE WHEN p_kind = 'cell' THEN c.cell_properties || v_item
                                                      ELSE c.cell_properties END,
                               instant_properties = CASE WHEN p_kind = 'instant' THEN c.instant_properties || v_item
                                                         ELSE c.instant_properties END
     WHERE c.classname = p_class
    RETURNING * INTO v_row;
    -- the table's first property column: a STATIC class registered without one (so left rows, nothing to chunk)
    -- takes the default storage now, as if registered with it (tgsis.chunk_class_by_default: when model 1 is in
    -- chunks and tgsis.storage is not rows; the rows just given the default move, verified)
    IF v_first AND tgsis.chunk_class_by_default(p_class) THEN
        SELECT * INTO v_row FROM tgsis.catalog c WHERE c.classname = p_class;
    END IF;
    RETURN v_row;
END
$$;

COMMENT ON FUNCTION tgsis.add_property(text, text, jsonb, text) IS
    'add a property to a feature class (tgsis_admin members), in every version: p_kind feature, cell (vertex or cell, of either alignment the class has a table for) or instant (temporal classes); stored rows get p_default (required for vertex and cell properties of a class with rows); the first vertex or cell property of a STATIC class''s table stores the class in chunks when model 1 is in chunks and tgsis.storage is not rows (tgsis.chunk_class_by_default); updates tgsis.catalog, the views and the versioning triggers; returns the catalog row';
