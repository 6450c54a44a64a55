-- tgsis.static_extent(geoid): bounding box and counts of a static (model-1) geometry from its vertex and simplex rows.
-- Model 1's extent function in the registry (tgsis.data_models), read by
-- tgsis.refresh_geometry. PL/pgSQL: the tables do not exist yet when the
-- extension script runs. Stored in chunks (tgsis.stored_in_chunks), the
-- counts are read from the chunk versions the session sees without decoding
-- them (a chunk's present ids: the length of its arrays less its holes; the
-- ref columns' relative or _wide array, whichever it holds) and the box from
-- the unnested coordinate arrays (min and max skip the holes' NULLs): the
-- face would decode every vertex and cell of the object to count them, and
-- every write path (upload, check-in, merge) recounts. The chunk tables'
-- row-level security gives the caller what the face would; a role that may
-- read the faces but not the chunk tables reads through the faces.
CREATE FUNCTION tgsis.static_extent(p_geoid bigint)
RETURNS TABLE (bbox cube, nvrtx bigint, ncell bigint)
LANGUAGE plpgsql
STABLE
SET search_path FROM CURRENT
AS $$
DECLARE
    v_table text;
    v_set   integer[];
    v_vis   text := '($2 IS NULL OR ((c.revision = ANY ($2)) IS TRUE AND (NOT c.revclosed OR NOT (c.lastrevs && $2))))';
BEGIN
    SELECT tgsis.simplex_table(g.geotype) INTO v_table FROM tgsis.geometry g WHERE g.geoid = p_geoid;
    IF v_table IS NULL THEN  -- none, or not in the session's version, or not the caller's to read
        RAISE EXCEPTION 'geometry % does not exist in this version', coalesce(p_geoid::text, 'NULL')
            USING ERRCODE = 'TG200', HINT = 'give the id of a stored geometry the session can read';
    END IF;
    IF tgsis.stored_in_chunks('vrtx') AND tgsis.stored_in_chunks(v_table)
       -- a role granted the faces only (not the storage) counts through them, as before the switch
       AND has_table_privilege('tgsis.vrtx_chunk', 'SELECT') AND has_table_privilege(format('tgsis.%I', v_table || '_chunk'), 'SELECT') THEN
        IF EXISTS (SELECT FROM tgsis.versioned_tables t WHERE t.schemaname = 'tgsis' AND t.tablename = 'vrtx') THEN
            v_set := tgsis.get_revisions(true);
        END IF;
        EXECUTE format('SELECT coalesce(sum(coalesce(cardinality(c.vrtxid1), cardinality(c.vrtxid1_wide))'
                       '                   - coalesce(cardinality(c.holes), 0)), 0)::bigint'
                       '  FROM tgsis.%I c WHERE c.geoid = $1 AND %s', v_table || '_chunk', v_vis)
           INTO ncell USING p_geoid, v_set;
        EXECUTE format('SELECT count(u.x), CASE WHEN count(u.x) > 0 THEN cube(ARRAY[min(u.x), min(u.y), min(u.z)], '
                       '                                              ARRAY[max(u.x), max(u.y), max(u.z)]) END'
                       '  FROM tgsis.vrtx_chunk c CROSS JOIN LATERAL unnest(c.x, c.y, c.z) AS u(x, y, z)'
                       ' WHERE c.geoid = $1 AND %s', v_vis)
           INTO nvrtx, bbox USING p_geoid, v_set;
        RETURN NEXT;
        RETURN;
    END IF;
    EXECUTE format('SELECT count(*) FROM tgsis.%I WHERE geoid = $1', v_table) INTO ncell USING p_geoid;
    SELECT count(*),
           CASE WHEN count(*) > 0 THEN cube(ARRAY[min(v.x), min(v.y), min(v.z)], ARRAY[max(v.x), max(v.y), max(v.z)]) END
      INTO nvrtx, bbox
      FROM tgsis.vrtx v WHERE v.geoid = p_geoid;
    RETURN NEXT;
END
$$;

COMMENT ON FUNCTION tgsis.static_extent(bigint) IS
    'bbox (cube of the vertices, NULL without any), number of vertices and of simplices of a static geometry from tgsis.vrtx and its simplex table; model 1''s extent function (tgsis.data_models)';
