-- tgsis.same_row_sql(table, a, b): the SQL condition that row versions a and b of a versioned table's storage hold the same content.
-- Content: every stored column but revision, lastrevs and the generated ones
-- (the columns tgsis.copy_object_state copies). It must be exact, as a row
-- it holds the same is not copied: true only when the two are one value,
-- never merely equal by the type's operator (-0.0 = 0.0, 1.0 = 1.00 in
-- numeric and jsonb, 'a' = 'A' under a nondeterministic collation), and
-- defined for types without an equality operator (json, point, xml, ...).
-- So floats (and arrays of them) are compared by their bits (float8send,
-- array_send: -0.0 is not 0.0, nor one NaN another); every other column by
-- its text from the type's output function (record_out, never a cast a
-- type's owner may have created), which is one text per value for the
-- built-in types under the settings tgsis.copy_object_state pins (floats
-- inside other types shortest-exact, timestamps ISO with their offset).
-- NULL is the same as NULL only. Returns 'true' for a table with no such
-- column.
CREATE FUNCTION tgsis.same_row_sql(p_t tgsis.versioned_tables, p_a text, p_b text)
RETURNS text
LANGUAGE sql
STABLE
SET search_path = pg_catalog, pg_temp
AS $$
    WITH RECURSIVE col AS (
        SELECT a.attnum, a.attname, a.atttypid AS typid
          FROM pg_catalog.pg_attribute a
         WHERE a.attrelid = (SELECT tgsis.storage_table(p_t.schemaname, p_t.tablename)::regclass)  -- once, not per catalog row
           AND a.attnum > 0 AND NOT a.attisdropped AND a.attgenerated = ''
           AND a.attname NOT IN ('revision', 'lastrevs')
        UNION ALL
        -- a domain's values are its base type's
        SELECT c.attnum, c.attname, t.typbasetype
          FROM col c JOIN pg_catalog.pg_type t ON t.oid = c.typid
         WHERE t.typtype = 'd'),
    base AS (
        SELECT c.attnum, c.attname,
               CASE c.typid WHEN 'float8'::regtype THEN 'float8send' WHEN 'float4'::regtype THEN 'float4send'
                            WHEN 'float8[]'::regtype THEN 'array_send' WHEN 'float4[]'::regtype THEN 'array_send'
                   END AS send
          FROM col c JOIN pg_catalog.pg_type t ON t.oid = c.typid
         WHERE t.typtype <> 'd')
    SELECT coalesce(pg_catalog.string_agg(x.cond, ' AND ' ORDER BY x.o), 'true')
      FROM (SELECT b.attnum AS o,
                   pg_catalog.format('pg_catalog.%s(%s.%I) IS NOT DISTINCT FROM pg_catalog.%s(%s.%I)',
                                     b.send, p_a, b.attname, b.send, p_b, b.attname) AS cond
              FROM base b WHERE b.send IS NOT NULL
            UNION ALL
            SELECT 0,
                   pg_catalog.format('pg_catalog.record_out(ROW(%s))::text = pg_catalog.record_out(ROW(%s))::text',
                                     pg_catalog.string_agg(pg_catalog.format('%s.%I', p_a, b.attname), ', ' ORDER BY b.attnum),
                                     pg_catalog.string_agg(pg_catalog.format('%s.%I', p_b, b.attname), ', ' ORDER BY b.attnum))
              FROM base b WHERE b.send IS NULL
            HAVING count(*) > 0) x
$$;

COMMENT ON FUNCTION tgsis.same_row_sql(tgsis.versioned_tables, text, text) IS
    'SQL condition: row versions p_a and p_b (aliases) of a versioned table''s storage hold exactly the same content (stored columns but revision, lastrevs and generated ones; floats by their bits, the rest by their output text); for tgsis.copy_object_state, which pins the settings that text depends on';
