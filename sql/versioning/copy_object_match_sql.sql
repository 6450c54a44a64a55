-- tgsis.copy_object_match_sql(table, own, other): the SQL condition that a row v tgsis.copy_object_state would write can be left alone.
-- True when v's key (the storage's: the table's keycolumns, or (geoid, chunk)
-- for chunk versions, tgsis.storage_key) has, among the rows of the
-- objects being copied ($1, in the key column's own type), exactly one row
-- satisfying p_own (v itself) and exactly one satisfying p_other, and that
-- one holds exactly v's content (tgsis.same_row_sql). p_own and p_other are
-- conditions on a row f of the storage over the parameters $1..$4 of
-- tgsis.copy_object_state's statements. The rows of the key are read by the
-- storage's primary key (keycolumns, revision), for v alone: a scalar
-- subquery per candidate, which the planner evaluates after the cheaper
-- conditions, so only the rows a merge would write are looked up.
-- Never NULL: false when in doubt (copying is always right).
CREATE FUNCTION tgsis.copy_object_match_sql(p_t tgsis.versioned_tables, p_own text, p_other text)
RETURNS text
LANGUAGE sql
STABLE
SET search_path = pg_catalog, pg_temp
AS $$
    SELECT pg_catalog.format(
        'coalesce((SELECT count(*) FILTER (WHERE %1$s) = 1 AND count(*) FILTER (WHERE %2$s) = 1
                          AND bool_and(%3$s) FILTER (WHERE %2$s)
                     FROM %4$s f
                    WHERE %6$s AND f.%7$I = ANY ($1::%8$s[])), false)',
        p_own, p_other, tgsis.same_row_sql(p_t, 'f', 'v'), tgsis.storage_table(p_t.schemaname, p_t.tablename), NULL,
        (SELECT pg_catalog.string_agg(pg_catalog.format('f.%1$I = v.%1$I', k), ' AND ' ORDER BY o)
           FROM pg_catalog.unnest(tgsis.storage_key(p_t)) WITH ORDINALITY AS u(k, o)),
        p_t.objectkeyfield, tgsis.object_key_type(p_t))
$$;

COMMENT ON FUNCTION tgsis.copy_object_match_sql(tgsis.versioned_tables, text, text) IS
    'SQL condition (never NULL) for tgsis.copy_object_state: row v''s key has exactly one row satisfying p_own and one satisfying p_other, holding exactly v''s content (tgsis.same_row_sql); read by the storage''s primary key';
