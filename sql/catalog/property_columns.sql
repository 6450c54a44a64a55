-- tgsis.property_columns(properties, per_cell, what): validated (name, type, size) of a property list.
-- Accepts {"name": "type", ...} or [["name", "type"], ...] or [{"name": ..., "type": ...}, ...];
-- a vertex or cell property may be a vector of k components: ["name", "type", k] or
-- {"name": ..., "type": ..., "size": k} (a file's ESIZES k property: one column, an array of k values);
-- a vertex or cell property may name its own alignment, {"name": ..., "type": ..., "alignment": "CELL"}
-- (alignment is per property: NULL here means the class's).
CREATE FUNCTION tgsis.property_columns(p_properties jsonb, p_per_cell boolean, p_what text)
RETURNS TABLE (name text, typename text, ord int, size int, alignment text)
LANGUAGE plpgsql
STABLE
AS $$
DECLARE
    v_pairs   jsonb;
    v_item    jsonb;
    v_name    text;
    v_type    text;
    v_canon   text;
    v_size    jsonb;
    v_align   text;
    v_seen    text[] := '{}';
    v_i       int := 0;
BEGIN
    IF p_properties IS NULL OR p_properties = 'null'::jsonb THEN
        RETURN;
    END IF;
    CASE jsonb_typeof(p_properties)
        WHEN 'object' THEN
            SELECT coalesce(jsonb_agg(jsonb_build_array(key, value)), '[]') INTO v_pairs FROM jsonb_each(p_properties);
        WHEN 'array' THEN
            v_pairs := p_properties;
        ELSE
            RAISE EXCEPTION '% properties must be a JSON object {"name": "type"} or an array of [name, type] pairs, not %',
                    p_what, jsonb_typeof(p_properties)
                USING ERRCODE = 'TG103';
    END CASE;

    FOR v_item IN SELECT value FROM jsonb_array_elements(v_pairs) LOOP
        v_i := v_i + 1;
        IF jsonb_typeof(v_item) = 'array' AND jsonb_array_length(v_item) IN (2, 3) THEN
            v_name := v_item ->> 0;
            v_type := v_item ->> 1;
            v_size := v_item -> 2;
        ELSIF jsonb_typeof(v_item) = 'object' THEN
            v_name := v_item ->> 'name';
            v_type := v_item ->> 'type';
            v_size := v_item -> 'size';
            v_align := upper(btrim(v_item ->> 'alignment'));
        ELSE
            RAISE EXCEPTION '% property % is %, expected [name, type] or {"name": ..., "type": ...}', p_what, v_i, v_item
                USING ERRCODE = 'TG103';
        END IF;
        IF v_align IS NOT NULL AND (v_align NOT IN ('VERTEX', 'CELL') OR NOT p_per_cell) THEN
            RAISE EXCEPTION '% property % has alignment %: only vertex and cell properties have one, VERTEX or CELL',
                    p_what, quote_literal(v_name), quote_literal(v_item ->> 'alignment')
                USING ERRCODE = 'TG103',
                      HINT = 'e.g. {"name": "facies", "type": "integer", "alignment": "CELL"} for a value per cell';
        END IF;
        IF v_size IS NOT NULL AND v_size <> 'null'::jsonb
           AND (jsonb_typeof(v_size) <> 'number' OR v_size::numeric NOT BETWEEN 1 AND 1000
                OR v_size::numeric <> trunc(v_size::numeric)) THEN
            RAISE EXCEPTION '% property % has size %: the number of components is a whole number 1 .. 1000', p_what,
                    quote_literal(v_name), v_size
                USING ERRCODE = 'TG103', HINT = 'e.g. ["slip", "float8", 3] for a vector of 3 components per vertex';
        END IF;

        -- names keep their letter case (a file's "Porosity" stays "Porosity"): the columns are
        -- quoted identifiers everywhere tgsis names them (format %I, psycopg sql.Identifier)
        IF v_name IS NULL OR v_name !~ '^[A-Za-z][A-Za-z0-9_]{0,62}$' THEN
            RAISE EXCEPTION '% property name % is not allowed', p_what, coalesce(quote_literal(v_name), 'NULL')
                USING ERRCODE = 'TG101',
                      DETAIL = 'Names must be letters (either case, kept as given), digits and underscores, '
                               'start with a letter and have at most 63 characters.',
                      HINT = 'Names starting with "_" are reserved for tgsis columns (_geoid, _idx); in SQL, quote '
                             'names with capitals or that are keywords: SELECT "Porosity" FROM ...';
        END IF;
        IF v_name = ANY (v_seen) THEN
            RAISE EXCEPTION '% property % is given twice', p_what, quote_literal(v_name) USING ERRCODE = 'TG103';
        END IF;
        v_seen := v_seen || v_name;

        SELECT t.typename INTO v_canon
          FROM tgsis.property_types t
         WHERE t.typename = lower(btrim(v_type)) OR lower(btrim(v_type)) = ANY (t.aliases);
        IF v_canon IS NULL THEN
            RAISE EXCEPTION '% property % has type %, which is not allowed', p_what, quote_literal(v_name),
                    coalesce(quote_literal(v_type), 'NULL')
                USING ERRCODE = 'TG103',
                      HINT = (SELECT 'allowed: ' || string_agg(t.typename, ', ' ORDER BY t.typename)
                                FROM tgsis.property_types t WHERE t.per_cell OR NOT p_per_cell);
        END IF;
        IF p_per_cell AND NOT (SELECT t.per_cell FROM tgsis.property_types t WHERE t.typename = v_canon) THEN
            RAISE EXCEPTION '% property % has type %: vertex and cell properties must be numbers or booleans',
                    p_what, quote_literal(v_name), v_canon
                USING ERRCODE = 'TG103',
                      HINT = (SELECT 'allowed: ' || string_agg(t.typename, ', ' ORDER BY t.typename)
                                FROM tgsis.property_types t WHERE t.per_cell);
        END IF;
        size := coalesce(CASE WHEN v_size <> 'null'::jsonb THEN v_size::numeric::int END, 1);
        IF size > 1 AND NOT p_per_cell THEN
            RAISE EXCEPTION '% property % has size %: only vertex and cell properties may be vectors', p_what,
                    quote_literal(v_name), size
                USING ERRCODE = 'TG103';
        END IF;
        name := v_name;
        typename := v_canon;
        ord := v_i;
        alignment := v_align;
        v_align := NULL;
        RETURN NEXT;
    END LOOP;
END
$$;

COMMENT ON FUNCTION tgsis.property_columns(jsonb, boolean, text) IS
    'validate a property list (names of letters in either case, digits and underscores, kept as given; types from tgsis.property_types; sizes of vector vertex/cell properties) and return it as ordered (name, typename, ord, size, alignment) rows';
