-- tgsis.cells_on_vertices_sql(k, ids, param): "the cell row v stands on one of these vertices", as SQL text.
-- For a statement over a model-1 cell storage (alias v, vertex columns vrtxid1..k) whose ids are bound
-- as parameter p_param ('$3'): the spans of the ids (cut at their 3 widest gaps, at most 4) that the
-- storage's vertex BRIN (tgsis.create_revision_indexes) is searched by, and after them the exact test
-- of the ids, hashed (+ 0: not an index condition: a BRIN searched by an = ANY is searched once per
-- id, 2,000 ids 0.66 s on a 2M-cell table, where the spans take milliseconds; docs/performance.md).
-- The spans are literals, so the planner sees where the change is. No ids (none but NULLs): false. The Python reader
-- cuts its spans the same way (tgsis.db._merge_states._id_spans).
CREATE FUNCTION tgsis.cells_on_vertices_sql(p_k integer, p_ids bigint[], p_param text)
RETURNS text
LANGUAGE plpgsql
IMMUTABLE
PARALLEL SAFE
SET search_path = pg_catalog, pg_temp
AS $$
BEGIN
    IF p_param IS NULL OR p_param !~ '^\$[0-9]+$' OR p_k IS NULL OR p_k NOT BETWEEN 1 AND 4 THEN
        RAISE EXCEPTION 'tgsis.cells_on_vertices_sql: % vertex columns bound as % (1 to 4 columns, a parameter such as $3)',
                p_k, quote_literal(p_param)
            USING ERRCODE = '22023';
    END IF;
    IF NOT EXISTS (SELECT FROM unnest(p_ids) AS x WHERE x IS NOT NULL) THEN  -- no ids (NULLs are none)
        RETURN 'false';
    END IF;
    RETURN (
        WITH ids AS (SELECT u.id, u.id::numeric - lag(u.id) OVER (ORDER BY u.id) AS gap  -- numeric: ids at both ends of bigint
                       FROM (SELECT DISTINCT x AS id FROM unnest(p_ids) AS x WHERE x IS NOT NULL) AS u),
        cuts AS (SELECT i.id FROM ids i WHERE i.gap > 1 ORDER BY i.gap DESC, i.id LIMIT 3),
        spans AS (SELECT min(g.id) AS lo, max(g.id) AS hi
                    FROM (SELECT i.id, count(c.id) OVER (ORDER BY i.id) AS grp FROM ids i LEFT JOIN cuts c ON c.id = i.id) AS g
                   GROUP BY g.grp)
        SELECT format('(%s) AND (%s)',
                      string_agg(format('v.vrtxid%s BETWEEN %L AND %L', k.i, s.lo, s.hi), ' OR ' ORDER BY k.i, s.lo),
                      (SELECT string_agg(format('(v.vrtxid%s + 0) = ANY (%s)', j, p_param), ' OR ' ORDER BY j)
                         FROM generate_series(1, p_k) AS j))
          FROM spans s, generate_series(1, p_k) AS k (i));
END
$$;

COMMENT ON FUNCTION tgsis.cells_on_vertices_sql(integer, bigint[], text) IS
    'SQL text of the condition "cell row v (vertex columns vrtxid1..k) stands on one of the ids bound as parameter p_param": spans of the ids for the storage''s vertex BRIN, then the exact hashed test';

-- internal to the merge by region: not executable by PUBLIC; the tgsis roles run it through
-- tgsis.mesh_merge_regions (which a reader may call directly, with its own rights) and the merge's functions
REVOKE ALL ON FUNCTION tgsis.cells_on_vertices_sql(integer, bigint[], text) FROM PUBLIC;
GRANT EXECUTE ON FUNCTION tgsis.cells_on_vertices_sql(integer, bigint[], text) TO tgsis_reader;
