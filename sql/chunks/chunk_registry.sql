-- tgsis.chunk_registry(table): what the chunk layer knows of a table it may chunk: a model table or a class's property table.
-- One registry for every function of this layer (docs/storage.md, "Property
-- chunks: the contract"): a model table is named bare ('vrtx': schema tgsis,
-- its row of tgsis.model_tables with chunkcolumn, chunkrefs, chunksize); a
-- feature class's property table is named schema-qualified and quoted as
-- format('%I.%I') gives it ('public.rock_cellpros'), and is known from
-- tgsis.catalog (the cellprotable of a STATIC, INSTANTS or EVOLVING class, or
-- its otherprotable (STATIC only):
-- the properties of the other alignment): chunked by _idx, keyed by _geoid,
-- no vertex-id columns, with the chunk size of the table its properties are
-- aligned with (vrtx for VERTEX, the geotype's simplex table for CELL; for
-- otherprotable the alignment other than the class's), so that chunk k of the
-- properties holds the values of chunk k of the vertices or cells. No list of tables is typed here. No row: the table
-- is not one the layer chunks (its callers raise TG200 by name).
-- PL/pgSQL, not SQL: a SQL function with SET is never inlined and, before PostgreSQL 18, plans its query
-- again at every call (0.40-0.47 ms a call on PostgreSQL 15, 0.20 ms in PL/pgSQL, which keeps the plan for
-- the session; a one-row write through a face called it 42 times, 20 now).
CREATE FUNCTION tgsis.chunk_registry(p_table text)
RETURNS TABLE (schemaname text, tablename text, keycolumn text, chunkcolumn text, chunkrefs text[], chunksize integer,
               classname text)
LANGUAGE plpgsql
STABLE
SET search_path = pg_catalog, pg_temp
AS $$
#variable_conflict use_column
BEGIN
    RETURN QUERY
    SELECT 'tgsis'::text, t.tablename, t.keycolumn, t.chunkcolumn, t.chunkrefs, t.chunksize, NULL::text
      FROM tgsis.model_tables t
     WHERE t.tablename = p_table
    UNION ALL
    SELECT c.schemaname, t.tablename, '_geoid'::text, '_idx'::text, '{}'::text[],
           coalesce((SELECT m.chunksize FROM tgsis.model_tables m
                      WHERE m.tablename = CASE WHEN t.alignment = 'VERTEX' THEN 'vrtx' ELSE tgsis.simplex_table(c.geotype) END),
                    (SELECT m.chunksize FROM tgsis.model_tables m WHERE m.tablename = 'vrtx')),
           c.classname
      FROM tgsis.catalog c
     CROSS JOIN LATERAL (VALUES (c.cellprotable, c.proalignment),
                                (c.otherprotable, CASE WHEN c.proalignment = 'VERTEX' THEN 'CELL' ELSE 'VERTEX' END))
                     AS t(tablename, alignment)
     WHERE strpos(p_table, '.') > 0  -- (a model table's bare name reads no row of the catalog)
       AND t.tablename IS NOT NULL AND format('%I.%I', c.schemaname, t.tablename) = p_table AND c.timemodel IN ('STATIC', 'INSTANTS', 'EVOLVING');
END
$$;

REVOKE ALL ON FUNCTION tgsis.chunk_registry(text) FROM PUBLIC;

COMMENT ON FUNCTION tgsis.chunk_registry(text) IS
    'what the chunk layer knows of a table: a model table named bare (tgsis.model_tables: chunkcolumn, chunkrefs, chunksize; schema tgsis) or a property table of a STATIC, INSTANTS or EVOLVING feature class (its cellprotable, or its otherprotable of the other alignment; a temporal class''s keyed by its instants too) named schema-qualified as format(''%I.%I'') quotes it (tgsis.catalog: chunked by _idx with the chunk size of the table it is aligned with, keyed by _geoid, classname set); no row for any other table';
