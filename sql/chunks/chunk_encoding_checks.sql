-- tgsis.chunk_encoding_checks(table): the conditions a chunk version c of tgsis.<table>_chunk meets when encoded as its readers read it.
-- One list for both places that check an encoding they did not write
-- themselves: the conversion's proof (tgsis.check_chunk_conversion, before a
-- storage switch returns) and the check of chunk versions a role other than
-- the owners inserts directly (tgsis.chunk_insert_check: the client's COPY
-- upload, or a hand-written INSERT). A chunk breaking one is read differently
-- by the readers (the decoded view by ordinality, tgsis.vertex by subscript,
-- the Python codec by holes): row storage cannot hold such a row (NOT NULL,
-- CHECKs), so the chunk storage must not either. The conditions (docs/storage.md,
-- "Chunks and the mapping of ids"): the arrays are one-dimensional, numbered
-- from 1, all of one length between 1 and the chunk size, NULL exactly at the
-- slots holes lists (ascending, not the last slot; holes NULL when none),
-- the double precision arrays present, and for vertex-id columns either vbase
-- with the relative integer arrays or the absolute _wide arrays, never both
-- nor neither, and vtop a bound of every vertex id of the chunk (else the
-- readers of the cells on given vertices would skip a chunk that holds some).
-- Returned as SQL boolean expressions over the alias c, built
-- from the registry (tgsis.chunk_columns); the caller ANDs them (NULL counts
-- as false). A class's property arrays (role 'value') may hold NULL at
-- present slots: only NULL at every hole is required of them. A vector
-- property (role 'vector', size k): a two-dimensional array from [1][1], the
-- chunk's length x k, each row all NULL (a NULL vector, or a hole: every hole
-- is) or without NULL (the row table refuses a NULL element): a row partly
-- NULL would read as a NULL vector. A point (role 'point'): a two-dimensional
-- double precision array from [1][1], the chunk's length x m, each row all
-- NULL exactly at the holes and without NULL at the present slots. Internal:
-- runs with the caller's rights.
CREATE FUNCTION tgsis.chunk_encoding_checks(p_table text)
RETURNS text[]
LANGUAGE plpgsql
STABLE
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_size integer;
    v_len  text;  -- the chunk version's length: its first value array's
BEGIN
    v_size := (SELECT r.chunksize FROM tgsis.chunk_registry(p_table) r);
    v_len := (SELECT CASE WHEN c.role IN ('float', 'value') THEN format('cardinality(c.%I)', c.name)
                          WHEN c.role IN ('vector', 'point') THEN format('array_length(c.%I, 1)', c.name)
                          ELSE format('cardinality(coalesce(c.%I, c.%I))', c.name, c.name || '_wide') END
                FROM tgsis.chunk_columns(p_table) c WHERE c.role IN ('float', 'ref', 'value', 'vector', 'point') ORDER BY c.colorder LIMIT 1);
    RETURN ARRAY[format('%s BETWEEN 1 AND %s', v_len, v_size),
                 format('(c.holes IS NULL OR (cardinality(c.holes) > 0 AND NOT (%s = ANY (c.holes))))', v_len)]
        -- (array_positions finds the NULLs in C: the check runs on every upload; the CASE keeps it from
        -- multidimensional arrays, which it refuses with an error of its own)
        || ARRAY(SELECT format('(c.%1$I IS NULL OR CASE WHEN array_ndims(c.%1$I) = 1 AND array_lower(c.%1$I, 1) = 1 '
                               'AND cardinality(c.%1$I) = %2$s THEN array_positions(c.%1$I, NULL) = '
                               'coalesce(c.holes::integer[], ''{}'') ELSE false END)',
                               a.col, v_len)
                   FROM (SELECT c.name AS col, c.colorder, 0 AS w FROM tgsis.chunk_columns(p_table) c WHERE c.role IN ('float', 'ref')
                         UNION ALL
                         SELECT c.name || '_wide', c.colorder, 1 FROM tgsis.chunk_columns(p_table) c WHERE c.role = 'ref') a
                  ORDER BY a.w, a.colorder)
        || ARRAY(SELECT format('c.%I IS NOT NULL', c.name) FROM tgsis.chunk_columns(p_table) c WHERE c.role = 'float'
                  ORDER BY c.colorder)
        -- a property's array: present, of the chunk's shape, NULL at every hole (a present slot may be NULL too)
        || ARRAY(SELECT format('(c.%1$I IS NOT NULL AND CASE WHEN array_ndims(c.%1$I) = 1 AND array_lower(c.%1$I, 1) = 1 '
                               'AND cardinality(c.%1$I) = %2$s THEN coalesce(c.holes::integer[], ''{}'') '
                               '<@ coalesce(array_positions(c.%1$I, NULL), ''{}'') ELSE false END)', c.name, v_len)
                   FROM tgsis.chunk_columns(p_table) c WHERE c.role = 'value' ORDER BY c.colorder)
        -- a vector property's 2-D array: present, the chunk's length x k from [1][1], each row all NULL or none, every
        -- hole's row NULL (one pass over its elements)
        || ARRAY(SELECT format('(c.%1$I IS NOT NULL AND CASE WHEN array_ndims(c.%1$I) = 2 AND array_lower(c.%1$I, 1) = 1 '
                               'AND array_lower(c.%1$I, 2) = 1 AND array_length(c.%1$I, 1) = %2$s AND array_length(c.%1$I, 2) = %3$s '
                               'THEN NOT EXISTS (SELECT FROM unnest(c.%1$I) WITH ORDINALITY AS e(x, n) GROUP BY (e.n - 1) / %3$s '
                               'HAVING count(e.x) NOT IN (0, %3$s) '
                               'OR (count(e.x) > 0 AND ((e.n - 1) / %3$s + 1) = ANY (coalesce(c.holes::bigint[], ''{}'')))) '
                               'ELSE false END)', c.name, v_len, c.size)
                   FROM tgsis.chunk_columns(p_table) c WHERE c.role = 'vector' ORDER BY c.colorder)
        -- a point's 2-D array: present, the chunk's length x m (m >= 1, the chunk's own) from [1][1], each row all
        -- NULL exactly at the holes and without NULL elsewhere (the row table refuses a NULL coordinate)
        || ARRAY(SELECT format('(c.%1$I IS NOT NULL AND CASE WHEN array_ndims(c.%1$I) = 2 AND array_lower(c.%1$I, 1) = 1 '
                               'AND array_lower(c.%1$I, 2) = 1 AND array_length(c.%1$I, 1) = %2$s '
                               'THEN NOT EXISTS (SELECT FROM unnest(c.%1$I) WITH ORDINALITY AS e(x, n) '
                               'GROUP BY (e.n - 1) / array_length(c.%1$I, 2) '
                               'HAVING count(e.x) NOT IN (0, array_length(c.%1$I, 2)) '
                               'OR (count(e.x) > 0) = (((e.n - 1) / array_length(c.%1$I, 2) + 1) '
                               '= ANY (coalesce(c.holes::bigint[], ''{}'')))) '
                               'ELSE false END)', c.name, v_len)
                   FROM tgsis.chunk_columns(p_table) c WHERE c.role = 'point' ORDER BY c.colorder)
        || ARRAY(SELECT format('(c.vbase IS NOT NULL) = (c.%1$I IS NOT NULL) AND (c.vbase IS NULL) = (c.%2$I IS NOT NULL)',
                               c.name, c.name || '_wide')
                   FROM tgsis.chunk_columns(p_table) c WHERE c.role = 'ref' ORDER BY c.colorder)
        -- vtop bounds every vertex id of the chunk (readers skip the chunks whose [vbase, vtop] misses the vertices
        -- they look for): relative, vtop - vbase at least twice every stored value (v1 - vbase + vK - v1 is then
        -- below it), unless vtop is the largest bigint; _wide, every id; tested in C (< ANY), no element unnested
        || CASE WHEN EXISTS (SELECT FROM tgsis.chunk_columns(p_table) c WHERE c.role = 'ref')
                THEN ARRAY['c.vtop IS NOT NULL AND (c.vbase IS NULL OR c.vtop >= c.vbase)'] ELSE '{}'::text[] END
        || ARRAY(SELECT format('(c.vbase IS NULL OR c.vtop = 9223372036854775807 '
                               'OR NOT coalesce((c.vtop - c.vbase) / 2 < ANY (c.%1$I), false)) '
                               'AND (c.vbase IS NOT NULL OR NOT coalesce(c.vtop < ANY (c.%2$I), false))',
                               c.name, c.name || '_wide')
                   FROM tgsis.chunk_columns(p_table) c WHERE c.role = 'ref' ORDER BY c.colorder);
END
$$;

REVOKE ALL ON FUNCTION tgsis.chunk_encoding_checks(text) FROM PUBLIC;

COMMENT ON FUNCTION tgsis.chunk_encoding_checks(text) IS
    'the conditions (SQL boolean expressions over the alias c) a chunk version of tgsis.<table>_chunk meets when encoded as its readers read it: arrays one-dimensional from 1, of one length between 1 and the chunk size, NULL exactly at holes, doubles present, refs either relative with vbase or absolute in _wide, vtop a bound of every vertex id; shared by tgsis.check_chunk_conversion and tgsis.chunk_insert_check';
