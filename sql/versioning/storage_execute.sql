-- tgsis.storage_execute(dml, sql, $1..$5): run one statement tgsis built over a versioned table's storage, with the caller's rights.
-- The body every storage statement of tgsis runs through: directly when the
-- caller may run it as itself, and inside each table's runner
-- (<table>_ver_run(), SECURITY DEFINER, owned by the table's owner) when
-- tgsis's definer code acts on a table another role owns (tgsis.storage_run).
-- A statement (p_dml) gives one row: its row count; a query gives its rows,
-- each one text[]. The parameters are $1 text[], $2 integer[], $3 integer[],
-- $4 integer, $5 bigint[]. It runs with the rights of whoever calls it, so
-- PUBLIC may call it: it is SQL the caller could run itself.
CREATE FUNCTION tgsis.storage_execute(
    p_dml boolean,
    p_sql text,
    p_1   text[],
    p_2   integer[],
    p_3   integer[],
    p_4   integer,
    p_5   bigint[])
RETURNS SETOF text[]
LANGUAGE plpgsql
VOLATILE
AS $$
DECLARE
    v_count bigint;
BEGIN
    IF p_dml THEN
        EXECUTE p_sql USING p_1, p_2, p_3, p_4, p_5;
        GET DIAGNOSTICS v_count = ROW_COUNT;
        RETURN NEXT ARRAY[v_count::text];
    ELSE
        RETURN QUERY EXECUTE p_sql USING p_1, p_2, p_3, p_4, p_5;
    END IF;
END
$$;

COMMENT ON FUNCTION tgsis.storage_execute(boolean, text, text[], integer[], integer[], integer, bigint[]) IS
    'run one statement (p_dml: its row count as one row) or query (its text[] rows) over versioned storage with the caller''s rights; $1..$5 = p_1..p_5; the body of every <table>_ver_run()';
