-- tgsis.chunk_object_extent(vertex table, cell table, geoid): an object's bounding box and counts read from the chunk versions the session sees, without decoding them; no row when they are not both readable chunks.
-- The extent functions of the registry (tgsis.data_models: model 1's
-- tgsis.static_extent, model 2's tgsis.instants_extent) are what every write
-- path's tgsis.refresh_geometry runs after it writes. Through the faces they
-- decode every vertex and cell of the object (of every instant, for model 2)
-- only to count them; here the cells are counted from each chunk's array
-- length less its holes (the first ref column of tgsis.model_tables.chunkrefs,
-- its relative array or its _wide one, whichever the chunk holds) and the
-- vertices and the box come from the unnested coordinate arrays (a hole's
-- NULL is skipped by count, min and max). Each chunk table is read with the
-- session's version when its table is versioned (tgsis.get_revisions: the
-- faces' own visibility test), and under the chunk tables' row-level
-- security, which gives the caller what the faces would. No row (the caller
-- reads the faces) when either table is stored as rows, or when the caller
-- may read the faces but not the chunk tables. Named tables are the chunk
-- layer's own (tgsis.model_tables, schema tgsis), never the caller's text.
CREATE FUNCTION tgsis.chunk_object_extent(p_vertex_table text, p_cell_table text, p_geoid bigint)
RETURNS TABLE (bbox cube, nvrtx bigint, ncell bigint)
LANGUAGE plpgsql
STABLE
SET search_path FROM CURRENT
AS $$
DECLARE
    v_ref  text;
    v_vset integer[];
    v_cset integer[];
    v_vis  text := '($2 IS NULL OR (' || tgsis.visible_versions('c', '$2') || '))';
BEGIN
    SELECT m.chunkrefs[1] INTO v_ref FROM tgsis.model_tables m WHERE m.tablename = p_cell_table;
    IF v_ref IS NULL OR NOT EXISTS (SELECT FROM tgsis.model_tables m WHERE m.tablename = p_vertex_table)
       OR NOT tgsis.stored_in_chunks(p_vertex_table) OR NOT tgsis.stored_in_chunks(p_cell_table)
       -- a role granted the faces only (not the storage) counts through them, as on rows
       OR NOT has_table_privilege(format('tgsis.%I', p_vertex_table || '_chunk'), 'SELECT')
       OR NOT has_table_privilege(format('tgsis.%I', p_cell_table || '_chunk'), 'SELECT') THEN
        RETURN;
    END IF;
    IF EXISTS (SELECT FROM tgsis.versioned_tables t WHERE t.schemaname = 'tgsis' AND t.tablename = p_vertex_table) THEN
        v_vset := tgsis.get_revisions(true);
    END IF;
    IF EXISTS (SELECT FROM tgsis.versioned_tables t WHERE t.schemaname = 'tgsis' AND t.tablename = p_cell_table) THEN
        v_cset := tgsis.get_revisions(true);
    END IF;
    EXECUTE format('SELECT coalesce(sum(coalesce(cardinality(c.%2$I), cardinality(c.%3$I)) - coalesce(cardinality(c.holes), 0)), 0)::bigint'
                   '  FROM tgsis.%1$I c WHERE c.geoid = $1 AND %4$s',
                   p_cell_table || '_chunk', v_ref, v_ref || '_wide', v_vis)
       INTO ncell USING p_geoid, v_cset;
    EXECUTE format('SELECT count(u.x), CASE WHEN count(u.x) > 0 THEN cube(ARRAY[min(u.x), min(u.y), min(u.z)], '
                   '                                              ARRAY[max(u.x), max(u.y), max(u.z)]) END'
                   '  FROM tgsis.%I c CROSS JOIN LATERAL unnest(c.x, c.y, c.z) AS u(x, y, z)'
                   ' WHERE c.geoid = $1 AND %s', p_vertex_table || '_chunk', v_vis)
       INTO nvrtx, bbox USING p_geoid, v_vset;
    RETURN NEXT;
END
$$;

COMMENT ON FUNCTION tgsis.chunk_object_extent(text, text, bigint) IS
    'bbox (cube of the vertices, NULL without any), number of vertices and of cells of an object whose vertex and cell tables (tgsis.model_tables) are both stored in chunks, read from the chunk versions the session sees without decoding them; no row when either is stored as rows or its chunk table is not the caller''s to read (read the faces then); shared by the registry''s extent functions';

-- executable by PUBLIC, as the extent functions that call it (every role that writes runs them as itself): it
-- runs with the caller's rights and reads only what the caller's faces would show (docs/storage.md names it)
