-- tgsis.chunk_table_of(table, with_view): the chunk table of a registered table, refused by name when it is missing.
-- Every function of this layer starts from a table name: it must be
-- registered for chunks (tgsis.chunk_columns: TG200, TG100), its chunk table
-- <schema>.<table>_chunk (tgsis.chunk_relation) must exist, and for the conversions its decoded view
-- <schema>.<table>_chunk_rows too. One function says so, with one message and
-- one hint, rather than a copy of the check in each caller.
CREATE FUNCTION tgsis.chunk_table_of(p_table text, p_with_view boolean DEFAULT false)
RETURNS regclass
LANGUAGE plpgsql
STABLE
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_chunk regclass;
BEGIN
    PERFORM FROM tgsis.chunk_columns(p_table);  -- TG200 / TG100
    v_chunk := to_regclass(tgsis.chunk_relation(p_table, '_chunk'));
    IF v_chunk IS NULL OR (p_with_view AND to_regclass(tgsis.chunk_relation(p_table, '_chunk_rows')) IS NULL) THEN
        RAISE EXCEPTION '% has no chunk table%', tgsis.chunk_relation(p_table, ''), CASE WHEN p_with_view THEN ' or no chunk view' ELSE '' END
            USING ERRCODE = 'TG200',
                  HINT = CASE WHEN p_with_view THEN 'create the chunk table and its view first' ELSE 'create the chunk table first' END;
    END IF;
    RETURN v_chunk;
END
$$;

REVOKE ALL ON FUNCTION tgsis.chunk_table_of(text, boolean) FROM PUBLIC;

COMMENT ON FUNCTION tgsis.chunk_table_of(text, boolean) IS
    '<schema>.<table>_chunk of a table of tgsis.chunk_registry (tgsis.chunk_relation); TG200 when the table is not registered or its chunk table (with p_with_view: or its decoded view <schema>.<table>_chunk_rows) does not exist, TG100 when its columns have no chunk form';
