-- tgsis.merge_value_text(schema, table): the SQL expression of a property row's values as one canonical text, and that of a missing row.
-- For the merge by region in SQL (tgsis.merge_property_rows): the columns of
-- a vertex or cell property table other than _geoid, _times (model 2's key), _timem, _timet (model 3's)
-- and _idx, in order (the values alone: tgsis.merge_solution_rows makes the same text of a solution's), as
-- a text[] literal over the row alias v: a float (real, double precision)
-- as float8 text with -0 as 0 (x + 0 is +0 for x = -0) and NULL as NaN, an
-- array of floats element by element, anything else as its text, NULL as
-- NaN. Equal texts are equal values as tgsis.merge3 compares them (NaN
-- equals NaN; a missing row reads as NaN everywhere: nulls). NULLs for a
-- table that is NULL or has no property column.
CREATE FUNCTION tgsis.merge_value_text(p_schema text, p_table text, OUT canon text, OUT nulls text)
LANGUAGE sql
STABLE
AS $$
    SELECT 'ARRAY[' || string_agg(
               CASE WHEN a.atttypid IN ('real'::regtype, 'double precision'::regtype)
                    THEN format('coalesce((v.%I::float8 + 0::float8)::text, ''NaN'')', a.attname)
                    WHEN a.atttypid IN ('real[]'::regtype, 'double precision[]'::regtype)
                    THEN format('coalesce((SELECT array_agg(coalesce((e::float8 + 0::float8)::text, ''NaN'') ORDER BY o)'
                                ' FROM unnest(v.%I) WITH ORDINALITY AS u(e, o))::text, ''NaN'')', a.attname)
                    ELSE format('coalesce(v.%I::text, ''NaN'')', a.attname) END, ', ' ORDER BY a.attnum) || ']::text',
           array_fill('NaN'::text, ARRAY[count(*)::integer])::text
      FROM pg_catalog.pg_attribute a
     WHERE a.attrelid = CASE WHEN p_table IS NOT NULL THEN pg_catalog.to_regclass(format('%I.%I', p_schema, p_table)) END
       AND a.attnum > 0 AND NOT a.attisdropped AND a.attname NOT IN ('_geoid', '_times', '_timem', '_timet', '_idx')
    HAVING count(*) > 0
$$;

COMMENT ON FUNCTION tgsis.merge_value_text(text, text) IS
    'the SQL expression (over alias v) of a property row''s values as one canonical text for the merge by region (floats exact, -0 as 0, NULL as NaN), and the text of a missing row; NULLs for no table or no property column';

-- internal to the merge by region: not executable by PUBLIC; the tgsis roles run it through
-- tgsis.mesh_merge_regions (which a reader may call directly, with its own rights) and the merge's functions
REVOKE ALL ON FUNCTION tgsis.merge_value_text(text, text) FROM PUBLIC;
GRANT EXECUTE ON FUNCTION tgsis.merge_value_text(text, text) TO tgsis_reader;
