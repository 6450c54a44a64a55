-- tgsis.fill_property_rows(class, values): give the stored features of a class that have no vertex or cell property rows one row per vertex or cell, in every version.
-- The repair for a class left unreadable ("... has 0 rows for N vertices")
-- by a vertex or cell property added by an earlier tgsis (0.2.0 and before) to a class
-- registered without one: the property is in the catalog and the table, but
-- the features stored before have no rows. p_values names a value for
-- every vertex or cell property of each table concerned ({"porosity": 0.2};
-- a vector property gets the value in each component). Geometries that have
-- rows keep them untouched; the rows made copy the versions and revisions of
-- the vertices or cells they stand for (tgsis.insert_property_rows), so
-- every version reads its features again. All or nothing: a value missing
-- or unreadable as its property's type, or a model keyed by time or cell
-- level, refuses the whole call. For members of tgsis_admin (SECURITY
-- DEFINER, as tgsis.add_property). Returns one row per property table of
-- the class: the geometries and rows (vertices or cells) given.
CREATE FUNCTION tgsis.fill_property_rows(p_class text, p_values jsonb)
RETURNS TABLE (tablename text, features bigint, rows bigint)
LANGUAGE plpgsql
VOLATILE
SECURITY DEFINER
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_class   tgsis.catalog := tgsis.class_for_change(p_class, 'fill');
    v_key     text;
    v_prop    record;
    v_table   text;
    v_missing bigint[];
    v_names   text[];
    v_exprs   text[];
    v_item    jsonb;
    v_value   text;
    v_made    record;
BEGIN
    IF p_values IS NULL OR jsonb_typeof(p_values) <> 'object' OR p_values = '{}' THEN
        RAISE EXCEPTION 'values % must be a JSON object {"property": value, ...}', coalesce(left(p_values::text, 200), 'NULL')
            USING ERRCODE = 'TG103', HINT = 'e.g. ''{"porosity": 0.2}''';
    END IF;
    FOR v_key IN SELECT jsonb_object_keys(p_values) LOOP
        PERFORM tgsis.class_property(v_class, v_key, 'cell');   -- TG103/TG200 naming an unknown property
        IF jsonb_typeof(p_values -> v_key) NOT IN ('string', 'number', 'boolean') THEN
            RAISE EXCEPTION 'value of property % must be a JSON string, number or boolean, not %', quote_literal(v_key),
                    left((p_values -> v_key)::text, 200)
                USING ERRCODE = 'TG103', HINT = 'a vector property gets the one value in each component';
        END IF;
    END LOOP;
    EXECUTE format('LOCK TABLE %s IN SHARE ROW EXCLUSIVE MODE', tgsis.storage_table(v_class.schemaname, v_class.featuretable));
    FOREACH v_table IN ARRAY array_remove(ARRAY[v_class.cellprotable, v_class.otherprotable], NULL) LOOP
        tablename := v_table;
        features := 0;
        rows := 0;
        v_names := '{}';
        v_exprs := '{}';
        FOR v_item IN SELECT p FROM jsonb_array_elements(v_class.cell_properties) p
                       WHERE (coalesce(p ->> 'alignment', v_class.proalignment) = v_class.proalignment) = (v_table = v_class.cellprotable)
        LOOP
            v_names := v_names || (v_item ->> 'name');
            IF p_values ? (v_item ->> 'name') THEN
                v_value := p_values ->> (v_item ->> 'name');
                BEGIN
                    EXECUTE format('SELECT %L::%s', v_value, v_item ->> 'type');
                EXCEPTION WHEN data_exception THEN
                    RAISE EXCEPTION 'value % of property % is not a valid %', quote_literal(left(v_value, 200)),
                            quote_literal(v_item ->> 'name'), v_item ->> 'type'
                        USING ERRCODE = 'TG103', DETAIL = left(SQLERRM, 500),
                              HINT = format('give a value PostgreSQL reads as %s', v_item ->> 'type');
                END;
                v_exprs := v_exprs || CASE WHEN (v_item ->> 'size')::integer > 1
                                           THEN format('array_fill(%L::%s, ARRAY[%s])', v_value, v_item ->> 'type',
                                                       (v_item ->> 'size')::integer)
                                           ELSE format('%L::%s', v_value, v_item ->> 'type') END;
            END IF;
        END LOOP;
        v_missing := tgsis.property_rows_missing(v_class, v_table);
        IF cardinality(v_missing) > 0 AND cardinality(v_names) > 0 THEN
            IF cardinality(v_exprs) < cardinality(v_names) THEN
                RAISE EXCEPTION 'feature class % has % stored geometries without rows in %, which need a value of every property of that table',
                        p_class, cardinality(v_missing), v_table
                    USING ERRCODE = 'TG103',
                          DETAIL = format('Values missing for: %s.', (SELECT string_agg(quote_literal(n), ', ')
                                                                         FROM unnest(v_names) n WHERE NOT p_values ? n)),
                          HINT = 'give p_values a value for each of them';
            END IF;
            SELECT * INTO v_made FROM tgsis.insert_property_rows(v_class, v_table, v_missing,
                (SELECT array_agg(n) FROM unnest(v_names) n WHERE p_values ? n), v_exprs);
            features := v_made.features;
            rows := v_made.rows;
        END IF;
        RETURN NEXT;
    END LOOP;
END
$$;

COMMENT ON FUNCTION tgsis.fill_property_rows(text, jsonb) IS
    'repair a class whose stored features have no vertex or cell property rows (a property added to a class registered without one, by tgsis 0.2.0 and before): each vertex or cell of them gets a row with the values of p_values ({"property": value}), in every version; tgsis_admin members; returns per property table the geometries and rows given';
