-- tgsis.chunk_columns(table): the columns of a table stored in chunks, each with its part in the chunk table.
-- The chunk table's creator (tgsis.create_chunk_table), its decoded face
-- (tgsis.create_chunk_view) and its writer (tgsis.write_chunk_rows) all
-- derive their column lists from here, so that they agree column for column
-- (the contract: docs/storage.md, "Chunks and the mapping of ids" and
-- "Property chunks: the contract"). Read from the registry
-- (tgsis.chunk_registry: a model table's row of tgsis.model_tables, or a
-- STATIC, INSTANTS or EVOLVING class's property table from tgsis.catalog) and from the live
-- definition of the row table (pg_attribute of what tgsis.row_shape names:
-- the table, or <table>_ver once versioned, whose versioning columns are left
-- out, or the shape table once stored in chunks), never from a list typed
-- here. Roles: 'key' (a primary-key column other than the chunk column: geoid,
-- and the time keys of later models), 'chunk' (the local-id column, replaced
-- by chunk = id >> log2(chunksize)), 'float' (a double precision column of a
-- model table: a double precision[] of the same name, never NULL but at
-- holes), 'ref' (a vertex-id column: integer[] relative to vbase, and
-- <name>_wide), 'value' (a property column of a class's table, or a model
-- table's scalar column that is neither a ref nor double precision, as a
-- G-map dart's acellid and positive: an array of its own type, smallint,
-- integer, bigint, real, double precision or boolean, whose elements may be
-- NULL: only holes marks a hole; a model table keeps at least one float or
-- ref column, NOT NULL, whose NULL marks the hole as before). typename is
-- the column's type (format_type). 'vector' (a class's vector property: a
-- column t[] of size k > 1 in tgsis.catalog, or, while tgsis.alter_chunk_table
-- adds or renames it before the catalog names it, in its own CHECK as the
-- class makes it; t one of the value types): a two-dimensional t[] (slots x k) in the chunk table, typename the ELEMENT
-- type and size k (NULL for every other role); a NULL vector is a row of k
-- NULLs there, which no vector of the row table is (its CHECK refuses a NULL
-- element). 'point' (a model table's double precision[] column: a G-map's
-- vertex, m coordinates, m per object: tgsis.gmap.embedding,
-- tgsis.md_gmap.embedding): a two-dimensional double precision[] (slots x m)
-- per chunk, m the chunk's own (array_length(arr, 2): a chunk holds one
-- object's points), typename double precision and size NULL; a hole is a row
-- of m NULLs, which no point is (the row table refuses a NULL coordinate),
-- and a slot is present where its first coordinate is not NULL
-- (docs/storage.md, "The points in chunks"). A column of any other type is
-- refused by name (TG100).
CREATE FUNCTION tgsis.chunk_columns(p_table text)
RETURNS TABLE (name text, role text, keyorder integer, colorder integer, typename text, size integer)
LANGUAGE plpgsql
STABLE
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_reg     record;
    v_storage regclass;
    v_bad     text;
    v_class   boolean;  -- a class's property table: its non-key columns are 'value's
    v_types   regtype[] := ARRAY['smallint', 'integer', 'bigint', 'real', 'double precision', 'boolean']::regtype[];
    v_arrays  regtype[] := ARRAY['smallint[]', 'integer[]', 'bigint[]', 'real[]', 'double precision[]', 'boolean[]']::regtype[];
    v_sizes   jsonb := '{}';  -- a class's vector properties: name -> k (tgsis.catalog; else their own CHECK)
BEGIN
    SELECT * INTO v_reg FROM tgsis.chunk_registry(p_table) r;
    IF NOT FOUND OR v_reg.chunkcolumn IS NULL THEN
        RAISE EXCEPTION '% is not registered for chunks',
                        CASE WHEN FOUND OR strpos(coalesce(p_table, ''), '.') = 0 THEN 'tgsis.' || coalesce(quote_ident(p_table), 'NULL')
                             ELSE p_table END
            USING ERRCODE = 'TG200',
                  DETAIL = CASE WHEN FOUND THEN 'Its row in tgsis.model_tables has no chunkcolumn: it is stored as rows.'
                                ELSE 'No row of tgsis.model_tables names it, nor is it the property table of a STATIC, INSTANTS or EVOLVING class '
                                     '(named schema.table) in tgsis.catalog.' END,
                  HINT = 'only the vertex and simplex tables registered with a chunk column have chunk tables';
    END IF;
    v_class := v_reg.classname IS NOT NULL;
    IF v_class THEN
        SELECT coalesce(jsonb_object_agg(p ->> 'name', (p ->> 'size')::integer), '{}') INTO v_sizes
          FROM tgsis.catalog c CROSS JOIN LATERAL jsonb_array_elements(c.cell_properties) AS p
         WHERE c.classname = v_reg.classname AND p ? 'size' AND (p ->> 'size')::integer > 1
           -- (the properties of this table: the class's alignment in cellprotable, the other's in otherprotable)
           AND (coalesce(p ->> 'alignment', c.proalignment) = c.proalignment) = (c.cellprotable = v_reg.tablename);
    END IF;
    v_storage := tgsis.row_shape(p_table);  -- the row storage, or its shape once stored in chunks
    IF v_storage IS NULL THEN
        RAISE EXCEPTION 'the storage of % does not exist', format('%I.%I', v_reg.schemaname, v_reg.tablename)
            USING ERRCODE = 'TG200', HINT = 'create the storage of the data models first';
    END IF;
    IF v_class THEN
        -- a vector property the catalog does not name yet: tgsis.alter_chunk_table adds or renames it before
        -- add_property / rename_property write the catalog. Its size is then read from its own CHECK on the row
        -- definition, exactly as the class makes it (k values from 1, none NULL); only the tables' owner alters it
        SELECT v_sizes || coalesce(jsonb_object_agg(a.attname, k.size), '{}') INTO v_sizes
          FROM pg_attribute a
          JOIN pg_constraint con ON con.conrelid = a.attrelid AND con.contype = 'c' AND con.conkey = ARRAY[a.attnum]
         CROSS JOIN LATERAL (SELECT (regexp_match(pg_get_expr(con.conbin, con.conrelid),
                                                  '\(cardinality\([^)]*\) = (\d+)\)'))[1]::integer AS size) k
         WHERE a.attrelid = v_storage AND a.attnum > 0 AND NOT a.attisdropped AND a.atttypid = ANY (v_arrays)
           AND NOT v_sizes ? a.attname AND k.size > 1
           AND pg_get_expr(con.conbin, con.conrelid)
               = format('((array_ndims(%1$I) = 1) AND (array_lower(%1$I, 1) = 1) AND (cardinality(%1$I) = %2$s) '
                        'AND (array_position(%1$I, NULL::%3$s) IS NULL))', a.attname, k.size,
                        format_type((SELECT t.typelem FROM pg_type t WHERE t.oid = a.atttypid), NULL));
    END IF;
    -- a class's property may be named anything its registration allows; the chunk table's own columns (chunk,
    -- revision, lastrevs, revclosed, holes, vbase, vtop) and the names this layer's generated SQL uses (slot, pad,
    -- o, q, w, ...: tgsis.chunk_reserved_names) may not: such a property would be dropped from the chunks (the
    -- versioning columns are left out of every row table) or break the statements that name it
    IF v_class THEN
        SELECT string_agg(quote_literal(a.attname), ', ' ORDER BY a.attnum) INTO v_bad
          FROM pg_attribute a
         WHERE a.attrelid = v_storage AND a.attnum > 0 AND NOT a.attisdropped
           AND a.attname NOT IN (v_reg.keycolumn, v_reg.chunkcolumn)
           AND a.attname = ANY (tgsis.chunk_reserved_names())
           -- (a versioned table's storage <table>_ver holds the versioning columns of these names itself)
           AND NOT (a.attname IN ('revision', 'lastrevs', 'revclosed')
                    AND EXISTS (SELECT FROM tgsis.versioned_tables t
                                 WHERE t.schemaname = v_reg.schemaname AND t.tablename = v_reg.tablename));
        IF v_bad IS NOT NULL THEN
            RAISE EXCEPTION 'the properties % of % have names the chunk layer uses itself', v_bad,
                            format('%I.%I', v_reg.schemaname, v_reg.tablename)
                USING ERRCODE = 'TG100',
                      DETAIL = format('A property stored in chunks may not be named as the chunk table''s own columns or the '
                                      'names its statements use: %s.',
                                      array_to_string(tgsis.chunk_reserved_names(), ', ')),
                      HINT = 'rename the property first (its values are kept), then store the class in chunks';
        END IF;
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
                WHEN v_class AND a.atttypid = ANY (v_types) THEN 'value'
                WHEN v_class AND a.atttypid = ANY (v_arrays) AND v_sizes ? a.attname THEN 'vector'
                WHEN v_class THEN NULL
                WHEN a.attname = ANY (v_reg.chunkrefs) AND a.atttypid = 'bigint'::regtype THEN 'ref'
                WHEN a.atttypid = 'double precision'::regtype AND NOT a.attname = ANY (v_reg.chunkrefs) THEN 'float'
                -- a model table's other scalar column (a G-map dart's acellid, positive: NULL allowed)
                WHEN a.atttypid = ANY (v_types) AND NOT a.attname = ANY (v_reg.chunkrefs) THEN 'value'
                -- a model table's point (a G-map's vertex: double precision[], m per object): a 2-D array per chunk
                WHEN a.atttypid = 'double precision[]'::regtype THEN 'point'
           END,
           pk.keyorder,
           row_number() OVER (ORDER BY a.attnum)::integer,
           CASE WHEN v_class AND a.atttypid = ANY (v_arrays) AND v_sizes ? a.attname AND pk.keyorder IS NULL
                THEN format_type((SELECT t.typelem FROM pg_type t WHERE t.oid = a.atttypid), NULL)
                WHEN NOT v_class AND a.atttypid = 'double precision[]'::regtype AND pk.keyorder IS NULL THEN 'double precision'
                ELSE format_type(a.atttypid, a.atttypmod) END,
           CASE WHEN v_class AND a.atttypid = ANY (v_arrays) AND pk.keyorder IS NULL THEN (v_sizes ->> a.attname)::integer END
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
       AND NOT (NOT v_class AND a.attname = ANY (v_reg.chunkrefs) AND a.atttypid = 'bigint'::regtype)
       AND NOT (NOT v_class AND a.atttypid = 'double precision'::regtype AND NOT a.attname = ANY (v_reg.chunkrefs))
       AND NOT (a.atttypid = ANY (v_types) AND NOT (NOT v_class AND a.attname = ANY (v_reg.chunkrefs)))
       AND NOT (v_class AND a.atttypid = ANY (v_arrays) AND v_sizes ? a.attname)
       AND NOT (NOT v_class AND a.atttypid = 'double precision[]'::regtype);
    IF v_class AND v_bad IS NULL
       AND NOT EXISTS (SELECT FROM pg_attribute a
                        WHERE a.attrelid = v_storage AND a.attnum > 0 AND NOT a.attisdropped
                          AND (a.atttypid = ANY (v_types) OR (a.atttypid = ANY (v_arrays) AND v_sizes ? a.attname))
                          AND a.attname NOT IN ('revision', 'lastrevs', 'revclosed', v_reg.chunkcolumn)
                          AND NOT EXISTS (SELECT FROM pg_constraint con WHERE con.conrelid = v_storage AND con.contype = 'p'
                                                                          AND a.attnum = ANY (con.conkey))) THEN
        v_bad := 'no property column (a chunk holds one array per property)';
    END IF;
    -- a model table's slot is present where its first double precision or vertex-id column is not NULL (those
    -- are NOT NULL in the row table; a 'value' column may be NULL at a present slot): it needs one
    IF NOT v_class AND v_bad IS NULL
       AND NOT EXISTS (SELECT FROM pg_attribute a
                        WHERE a.attrelid = v_storage AND a.attnum > 0 AND NOT a.attisdropped
                          AND a.attname NOT IN ('revision', 'lastrevs', 'revclosed', v_reg.chunkcolumn)
                          AND ((a.atttypid = 'double precision'::regtype AND NOT a.attname = ANY (v_reg.chunkrefs))
                               OR a.atttypid = 'double precision[]'::regtype
                               OR (a.atttypid = 'bigint'::regtype AND a.attname = ANY (v_reg.chunkrefs)))
                          AND NOT EXISTS (SELECT FROM pg_constraint con WHERE con.conrelid = v_storage AND con.contype = 'p'
                                                                          AND a.attnum = ANY (con.conkey))) THEN
        v_bad := 'no double precision nor vertex-id column (a model table''s slot is present where the first is not NULL)';
    END IF;
    -- the readers unnest a class's arrays side by side in one call (a vector as its k components) and the writer
    -- with two more (slot, _delete): PostgreSQL passes at most 100 arguments to a function (FUNC_MAX_ARGS)
    IF v_class AND v_bad IS NULL
       AND (SELECT count(*) FILTER (WHERE NOT v_sizes ? a.attname) + coalesce(sum((v_sizes ->> a.attname)::integer), 0)
              FROM pg_attribute a
             WHERE a.attrelid = v_storage AND a.attnum > 0 AND NOT a.attisdropped
               AND a.attname NOT IN ('revision', 'lastrevs', 'revclosed', v_reg.keycolumn, v_reg.chunkcolumn)) > 98 THEN
        v_bad := 'more than 98 property values a slot (a vector counts its size): the chunk readers unnest them in one call';
    END IF;
    IF v_bad IS NOT NULL
       OR NOT EXISTS (SELECT FROM pg_constraint con JOIN pg_attribute a ON a.attrelid = con.conrelid AND a.attnum = ANY (con.conkey)
                       WHERE con.conrelid = v_storage AND con.contype = 'p' AND a.attname = v_reg.chunkcolumn
                         AND a.atttypid = 'bigint'::regtype)
       OR EXISTS (SELECT FROM unnest(v_reg.chunkrefs) AS r(c)
                   WHERE NOT EXISTS (SELECT FROM pg_attribute a WHERE a.attrelid = v_storage AND a.attname = r.c
                                                                 AND NOT a.attisdropped AND a.atttypid = 'bigint'::regtype)) THEN
        RAISE EXCEPTION '% does not fit the chunk layout', format('%I.%I', v_reg.schemaname, v_reg.tablename)
            USING ERRCODE = 'TG100',
                  DETAIL = CASE WHEN v_class
                                THEN format('The chunk column %s must be a bigint of the primary key, every property a scalar '
                                            'smallint, integer, bigint, real, double precision or boolean, or a vector of '
                                            'them the catalog gives a size; not so: %s.', v_reg.chunkcolumn, coalesce(v_bad, 'the chunk column'))
                                ELSE format('The chunk column %s must be a bigint of the primary key, the ref columns %s bigint '
                                            'columns, every other non-key column double precision or a scalar smallint, '
                                            'integer, bigint, real or boolean, and one a double precision or ref column; not so: %s.',
                                            v_reg.chunkcolumn, v_reg.chunkrefs, coalesce(v_bad, 'the chunk or ref columns')) END,
                  HINT = 'register the table with chunkcolumn NULL (stored as rows) until the layout has a form for these columns';
    END IF;
END
$$;

REVOKE ALL ON FUNCTION tgsis.chunk_columns(text) FROM PUBLIC;

COMMENT ON FUNCTION tgsis.chunk_columns(text) IS
    'the columns of a table of tgsis.chunk_registry (a model table registered for chunks, or the property table of a STATIC, INSTANTS or EVOLVING class named schema.table), from its live storage, in column order, each with its role in the chunk table: key, chunk (the local id), float (double precision[]), ref (integer[] relative to vbase, and <name>_wide) or value (a property, or a model table''s other scalar column: an array of its type, NULL elements allowed) or vector (a class''s vector property of size k: a 2-D array, slots x k, typename its element type, size k) or point (a model table''s double precision[]: a 2-D array, slots x m, m per chunk, size NULL), and its type; TG200 for a table not registered for chunks, TG100 for a column the layout has no form for';
