-- tgsis.merge_row_texts(table, skipped columns): the SQL expressions a psql merge of a temporal surface reads a row's values with, as text.
-- Shared by tgsis.merge_instants_by_slice and tgsis.merge_periods_by_slice,
-- which compare rows as the Python merge does: over the columns of p_table
-- but p_skip (the object and key columns), in their order, of a row v:
-- p_vals the values as text (for writing; NULL stays NULL), p_bits exact
-- (NULL as NaN: the rows' bits, as the Python writer compares them), p_eq
-- as tgsis._merge_slices.same_state compares them (floats + 0, so -0 as 0;
-- NULL as NaN). Each a comma-separated list ('' for none), names quoted with
-- %I. The caller pins extra_float_digits: floats as text are exact.
CREATE FUNCTION tgsis.merge_row_texts(p_table regclass, p_skip text[], OUT p_vals text, OUT p_bits text, OUT p_eq text)
LANGUAGE sql
STABLE
SET search_path = pg_catalog, pg_temp
AS $$
    SELECT coalesce(string_agg(format('v.%I::text', a.attname), ', ' ORDER BY a.attnum), ''),
           coalesce(string_agg(format('coalesce(v.%I::text, ''NaN'')', a.attname), ', ' ORDER BY a.attnum), ''),
           coalesce(string_agg(CASE WHEN a.atttypid IN ('real'::regtype, 'double precision'::regtype)
                                    THEN format('coalesce((v.%I::float8 + 0::float8)::text, ''NaN'')', a.attname)
                                    ELSE format('coalesce(v.%I::text, ''NaN'')', a.attname) END, ', ' ORDER BY a.attnum), '')
      FROM pg_catalog.pg_attribute a
     WHERE a.attrelid = p_table AND a.attnum > 0 AND NOT a.attisdropped AND a.attname <> ALL (p_skip)
$$;

-- internal to the psql merges, not executable by PUBLIC (tests/test_function_grants.py)
REVOKE ALL ON FUNCTION tgsis.merge_row_texts(regclass, text[]) FROM PUBLIC;

COMMENT ON FUNCTION tgsis.merge_row_texts(regclass, text[]) IS
    'the SQL expression lists (values as text, exact bits, values as the Python merge compares them) over a table''s columns but the skipped ones, with which the psql merges of temporal surfaces read rows';
