-- tgsis.object_key_sql(type, expression): the SQL expression that turns an object key of a type into its canonical text.
-- For the code that versioning generates (the views' write triggers, dynamic
-- SQL on storage): for types whose cast to text depends on no setting it is
-- the cast itself (the generated code of integer and text keys stays what
-- it was), for the others a call of tgsis.object_key_text, for reg* types
-- the oid (their text follows search_path and renames). NULL for a type
-- with no canonical text: arrays, ranges, json, money (lc_monetary) and
-- others; tgsis.check_key_type refuses them as object keys.
CREATE FUNCTION tgsis.object_key_sql(p_type oid, p_expr text)
RETURNS text
LANGUAGE sql
IMMUTABLE
PARALLEL SAFE
AS $$
    SELECT CASE
        WHEN p_type IN (20, 21, 23, 26, 16, 25, 1043, 1042, 19, 18, 2950, 869, 650, 829, 774, 1560, 1562, 3220, 5069, 27,
                        1083, 1266)
            -- int8, int2, int4, oid, bool, text, varchar, bpchar (its cast drops the padding its equality ignores),
            -- name, "char", uuid, inet, cidr, macaddr, macaddr8, bit, varbit, pg_lsn, xid8, tid, time, timetz
            THEN p_expr || '::text'
        WHEN p_type IN (1082, 1114, 1184, 700, 701, 1700, 1186, 17)
            -- date, timestamp, timestamptz, float4, float8, numeric, interval, bytea
            THEN 'tgsis.object_key_text(' || p_expr || ')'
        WHEN p_type IN (2205, 24, 2206, 4096, 4089, 3734, 3769, 2203, 2204, 2202, 4191)
            -- regclass, regproc, regtype, regrole, regnamespace, regconfig, regdictionary, regoper, regoperator,
            -- regprocedure, regcollation: the oid
            THEN p_expr || '::pg_catalog.oid::pg_catalog.text'
        END
$$;

COMMENT ON FUNCTION tgsis.object_key_sql(oid, text) IS
    'SQL expression giving the canonical text (independent of the session''s settings) of an object key of type p_type computed by p_expr; NULL for types without one';
