-- tgsis.instants_extent(geoid): bounding box and counts of a surface at instants (model 2) over all its instants.
-- Model 2's extent function in the registry (tgsis.data_models), read by
-- tgsis.refresh_geometry, which every write path runs. With the time tables
-- stored in chunks the counts and the box are read from the chunk versions
-- the session sees without decoding them (tgsis.chunk_object_extent): the
-- faces would decode every vertex and triangle of every instant only to count
-- them. A role that may read the faces but not the chunk tables reads through
-- the faces.
CREATE FUNCTION tgsis.instants_extent(p_geoid bigint)
RETURNS TABLE (bbox cube, nvrtx bigint, ncell bigint)
LANGUAGE plpgsql
STABLE
SET search_path FROM CURRENT
AS $$
BEGIN
    RETURN QUERY SELECT * FROM tgsis.chunk_object_extent('times_vrtx', 'times_trgl', p_geoid);
    IF FOUND THEN
        RETURN;
    END IF;
    SELECT count(*) INTO ncell FROM tgsis.times_trgl c WHERE c.geoid = p_geoid;
    SELECT count(*),
           CASE WHEN count(*) > 0 THEN cube(ARRAY[min(v.x), min(v.y), min(v.z)], ARRAY[max(v.x), max(v.y), max(v.z)]) END
      INTO nvrtx, bbox
      FROM tgsis.times_vrtx v WHERE v.geoid = p_geoid;
    RETURN NEXT;
END
$$;

COMMENT ON FUNCTION tgsis.instants_extent(bigint) IS
    'bbox of every vertex at every instant, number of vertex rows and of triangle rows of a surface at instants (model 2); model 2''s extent function (tgsis.data_models)';
