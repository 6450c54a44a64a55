-- tgsis.class_property(class, name, kind): which list and table of a class hold the property called name.
-- A class's properties are in three lists of tgsis.catalog: feature_properties
-- (columns of the feature table), cell_properties (vertex or cell properties:
-- columns of cellprotable, or of otherprotable for those aligned otherwise)
-- and instant_properties (columns of protablename). A name may be in more
-- than one list; p_kind ('feature', 'cell', 'instant') then says which.
-- The key and time columns (_geoid, _idx, _times, _timem, _timet) are no
-- properties: they are refused by name.
CREATE FUNCTION tgsis.class_property(p_class tgsis.catalog, p_name text, p_kind text DEFAULT NULL)
RETURNS TABLE (kind text, tablename text, item jsonb)
LANGUAGE plpgsql
STABLE
AS $$
DECLARE
    v_found record;
    v_count integer;
BEGIN
    IF p_kind IS NOT NULL AND p_kind NOT IN ('feature', 'cell', 'instant') THEN
        RAISE EXCEPTION 'property kind % must be feature, cell or instant', quote_literal(p_kind)
            USING ERRCODE = 'TG100',
                  HINT = 'feature: a value per feature; cell: per vertex or cell; instant: per feature and instant';
    END IF;
    IF p_name LIKE '\_%' OR p_name IN ('revision', 'lastrevs', 'revclosed') THEN
        RAISE EXCEPTION 'column % of feature class % is a key, time or versioning column, not a property',
                quote_literal(p_name), p_class.classname
            USING ERRCODE = 'TG101', DETAIL = 'Columns starting with "_" and revision, lastrevs, revclosed are tgsis''s own.';
    END IF;
    SELECT count(*) INTO v_count
      FROM (SELECT 'feature' AS k, p FROM jsonb_array_elements(p_class.feature_properties) p
            UNION ALL SELECT 'cell', p FROM jsonb_array_elements(p_class.cell_properties) p
            UNION ALL SELECT 'instant', p FROM jsonb_array_elements(p_class.instant_properties) p) l
     WHERE l.p ->> 'name' = p_name AND (p_kind IS NULL OR l.k = p_kind);
    IF v_count = 0 THEN
        RAISE EXCEPTION 'feature class % has no %property %', p_class.classname,
                coalesce(p_kind || ' ', ''), coalesce(quote_literal(p_name), 'NULL')
            USING ERRCODE = 'TG103',
                  DETAIL = format('Its properties: %s.', coalesce(nullif(concat_ws('; ',
                      'feature: ' || (SELECT string_agg(p ->> 'name', ', ') FROM jsonb_array_elements(p_class.feature_properties) p),
                      'cell: ' || (SELECT string_agg(p ->> 'name', ', ') FROM jsonb_array_elements(p_class.cell_properties) p),
                      'instant: ' || (SELECT string_agg(p ->> 'name', ', ') FROM jsonb_array_elements(p_class.instant_properties) p)),
                      ''), 'none')),
                  HINT = format('SELECT feature_properties, cell_properties, instant_properties FROM tgsis.catalog WHERE classname = %L',
                                p_class.classname);
    ELSIF v_count > 1 THEN
        RAISE EXCEPTION 'feature class % has more than one property %', p_class.classname, quote_literal(p_name)
            USING ERRCODE = 'TG103', HINT = 'say which: p_kind => ''feature'', ''cell'' or ''instant''';
    END IF;
    FOR v_found IN
        SELECT 'feature' AS k, p, p_class.featuretable AS t FROM jsonb_array_elements(p_class.feature_properties) p
        UNION ALL
        SELECT 'cell', p, CASE WHEN p ? 'alignment' THEN p_class.otherprotable ELSE p_class.cellprotable END
          FROM jsonb_array_elements(p_class.cell_properties) p
        UNION ALL
        SELECT 'instant', p, p_class.protablename FROM jsonb_array_elements(p_class.instant_properties) p
    LOOP
        IF v_found.p ->> 'name' = p_name AND (p_kind IS NULL OR v_found.k = p_kind) THEN
            kind := v_found.k;
            tablename := v_found.t;
            item := v_found.p;
            RETURN NEXT;
        END IF;
    END LOOP;
END
$$;

COMMENT ON FUNCTION tgsis.class_property(tgsis.catalog, text, text) IS
    'the kind (feature, cell, instant), table and catalog item of the property p_name of a class; TG103 when it has none or more than one (then p_kind says which), TG101 for key, time and versioning columns';
