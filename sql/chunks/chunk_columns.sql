-- tgsis.chunk_columns(table): the columns of a model table stored in chunks, each with its part in the chunk table.
-- The chunk table's creator (tgsis.create_chunk_table), its decoded face
-- (tgsis.create_chunk_view) and its writer (tgsis.write_chunk_rows) all
-- derive their column lists from here, so that they agree column for column
-- (the contract: docs/storage.md, "Chunks and the mapping of ids"). Read from
-- the registry (tgsis.model_tables: chunkcolumn, chunkrefs, chunksize) and from
-- the live definition of the row table (pg_attribute of what tgsis.row_shape
-- names: the table, or <table>_ver once versioned, whose versioning columns are
-- left out, or the shape table once stored in chunks), never from a list typed here. Roles: 'key' (a primary-key column
-- other than the chunk column: geoid, and the time keys of later models),
-- 'chunk' (the local-id column, replaced by chunk = id >> log2(chunksize)),
-- 'float' (a double precision column: a double precision[] of the same name),
-- 'ref' (a vertex-id column: integer[] relative to vbase, and <name>_wide).
-- A column of any other type is refused by name (TG100): the contract has no
-- array form for it yet.
CREATE FUNCTION tgsis.chunk_columns(p_table text)
RETURNS TABLE (name text, role text, keyorder integer, colorder integer)
LANGUAGE plpgsql
STABLE
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_reg     tgsis.model_tables;
    v_storage regclass;
    v_bad     text;
BEGIN
    SELECT * INTO v_reg FROM tgsis.model_tables t WHERE t.tablename = p_table;
    IF NOT FOUND OR v_reg.chunkcolumn IS NULL THEN
        RAISE EXCEPTION 'tgsis.% is not registered for chunks', coalesce(quote_ident(p_table), 'NULL')
            USING ERRCODE = 'TG200',
                  DETAIL = CASE WHEN FOUND THEN 'Its row in tgsis.model_tables has no chunkcolumn: it is stored as rows.'
                                ELSE 'No row of tgsis.model_tables names it.' END,
                  HINT = 'only the vertex and simplex tables registered with a chunk column have chunk tables';
    END IF;
    v_storage := tgsis.row_shape(p_table);  -- the row storage, or its shape once stored in chunks
    IF v_storage IS NULL THEN
        RAISE EXCEPTION 'the storage of tgsis.% does not exist', quote_ident(p_table)
            USING ERRCODE = 'TG200', HINT = 'create the storage of the data models first';
    END IF;
    RETURN QUERY
    WITH pk AS (
        SELECT a.attname::text AS name, k.ord::integer AS keyorder
          FROM pg_constraint con
         CROSS JOIN LATERAL unnest(con.conkey) WITH ORDINALITY AS k(attnum, ord)
          JOIN pg_attribute a ON a.attrelid = con.conrelid AND a.attnum = k.attnum
         WHERE con.conrelid = v_storage AND con.contype = 'p' AND a.attname <> 'revision'
    )
    SELECT a.attname::text,
           CASE WHEN a.attname = v_reg.chunkcolumn THEN 'chunk'
                WHEN pk.keyorder IS NOT NULL THEN 'key'
                WHEN a.attname = ANY (v_reg.chunkrefs) AND a.atttypid = 'bigint'::regtype THEN 'ref'
                WHEN a.atttypid = 'double precision'::regtype AND NOT a.attname = ANY (v_reg.chunkrefs) THEN 'float'
           END,
           pk.keyorder,
           row_number() OVER (ORDER BY a.attnum)::integer
      FROM pg_attribute a LEFT JOIN pk ON pk.name = a.attname
     WHERE a.attrelid = v_storage AND a.attnum > 0 AND NOT a.attisdropped
       AND a.attname NOT IN ('revision', 'lastrevs', 'revclosed')
     ORDER BY a.attnum;
    -- what the contract cannot store, refused by name rather than stored otherwise
    SELECT string_agg(format('%I %s', a.attname, format_type(a.atttypid, a.atttypmod)), ', ' ORDER BY a.attnum) INTO v_bad
      FROM pg_attribute a
     WHERE a.attrelid = v_storage AND a.attnum > 0 AND NOT a.attisdropped
       AND a.attname NOT IN ('revision', 'lastrevs', 'revclosed')
       AND a.attname <> v_reg.chunkcolumn
       AND NOT EXISTS (SELECT FROM pg_constraint con WHERE con.conrelid = v_storage AND con.contype = 'p'
                                                       AND a.attnum = ANY (con.conkey))
       AND NOT (a.attname = ANY (v_reg.chunkrefs) AND a.atttypid = 'bigint'::regtype)
       AND NOT (a.atttypid = 'double precision'::regtype AND NOT a.attname = ANY (v_reg.chunkrefs));
    IF v_bad IS NOT NULL
       OR NOT EXISTS (SELECT FROM pg_constraint con JOIN pg_attribute a ON a.attrelid = con.conrelid AND a.attnum = ANY (con.conkey)
                       WHERE con.conrelid = v_storage AND con.contype = 'p' AND a.attname = v_reg.chunkcolumn
                         AND a.atttypid = 'bigint'::regtype)
       OR EXISTS (SELECT FROM unnest(v_reg.chunkrefs) AS r(c)
                   WHERE NOT EXISTS (SELECT FROM pg_attribute a WHERE a.attrelid = v_storage AND a.attname = r.c
                                                                 AND NOT a.attisdropped AND a.atttypid = 'bigint'::regtype)) THEN
        RAISE EXCEPTION 'tgsis.% does not fit the chunk layout', quote_ident(p_table)
            USING ERRCODE = 'TG100',
                  DETAIL = format('The chunk column %s must be a bigint of the primary key, the ref columns %s bigint '
                                  'columns, every other non-key column double precision; not so: %s.',
                                  v_reg.chunkcolumn, v_reg.chunkrefs, coalesce(v_bad, 'the chunk or ref columns')),
                  HINT = 'register the table with chunkcolumn NULL (stored as rows) until the layout has a form for these columns';
    END IF;
END
$$;

REVOKE ALL ON FUNCTION tgsis.chunk_columns(text) FROM PUBLIC;

COMMENT ON FUNCTION tgsis.chunk_columns(text) IS
    'the columns of a model table registered for chunks (tgsis.model_tables.chunkcolumn), from its live storage, in column order, each with its role in the chunk table: key, chunk (the local id), float (double precision[]) or ref (integer[] relative to vbase, and <name>_wide); TG200 for a table not registered for chunks, TG100 for a column the layout has no form for';
