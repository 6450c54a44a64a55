-- tgsis.static_extent(geoid): bounding box and counts of a static (model-1) geometry from its vertex and simplex rows.
-- Model 1's extent function in the registry (tgsis.data_models), read by
-- tgsis.refresh_geometry. PL/pgSQL: the tables do not exist yet when the
-- extension script runs. Stored in chunks (tgsis.stored_in_chunks), the
-- counts and the box are read from the chunk versions the session sees
-- without decoding them (tgsis.chunk_object_extent): the face would decode
-- every vertex and cell of the object to count them, and every write path
-- (upload, check-in, merge) recounts. A role that may read the faces but not
-- the chunk tables reads through the faces.
CREATE FUNCTION tgsis.static_extent(p_geoid bigint)
RETURNS TABLE (bbox cube, nvrtx bigint, ncell bigint)
LANGUAGE plpgsql
STABLE
SET search_path FROM CURRENT
AS $$
DECLARE
    v_table text;
BEGIN
    SELECT tgsis.simplex_table(g.geotype) INTO v_table FROM tgsis.geometry g WHERE g.geoid = p_geoid;
    IF v_table IS NULL THEN  -- none, or not in the session's version, or not the caller's to read
        RAISE EXCEPTION 'geometry % does not exist in this version', coalesce(p_geoid::text, 'NULL')
            USING ERRCODE = 'TG200', HINT = 'give the id of a stored geometry the session can read';
    END IF;
    RETURN QUERY SELECT * FROM tgsis.chunk_object_extent('vrtx', v_table, p_geoid);
    IF FOUND THEN
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
