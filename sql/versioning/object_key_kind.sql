-- tgsis.object_key_kind(type): how an object key of a type becomes canonical text, or NULL when it cannot.
-- 'cast': the type's cast to text depends on no setting (integers, text,
-- uuid, time, ...); 'function': tgsis.object_key_text writes it (date,
-- timestamp(tz), floats, numeric, interval, bytea); NULL: arrays, ranges,
-- json, money (lc_monetary), tsvector, the reg* types (their text follows
-- search_path and renames, and text reads back as a name, never as an oid)
-- and every other type, whose text may depend on the session or differ for
-- equal values.
CREATE FUNCTION tgsis.object_key_kind(p_type oid)
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
            THEN 'cast'
        WHEN p_type IN (1082, 1114, 1184, 700, 701, 1700, 1186, 17)
            -- date, timestamp, timestamptz, float4, float8, numeric, interval, bytea
            THEN 'function'
        END
$$;

COMMENT ON FUNCTION tgsis.object_key_kind(oid) IS
    'how an object key of type p_type gets its canonical text: cast (its cast to text), function (tgsis.object_key_text), NULL (no canonical text: refused as object key)';
