-- tgsis.md_vertices_in_box(geoid, axes, low, high): the points of a multiply indexed G-map inside a box over some of its axes.
-- E.g. the part of a horizon's interpretations between knowledge 1 and 2
-- over an x-y window. The points are GiST-indexed as cubes
-- (md_vertex_point_idx); the box is unbounded on the axes not given. An
-- axis the G-map does not have is refused (TG100, naming it and the G-map's
-- axes) rather than answered with no point. The box is closed (a point on
-- its face is inside). A point with a NaN coordinate is in no box: it has
-- no position (tgsis.check_md_geometry reports it), and the cube type's
-- comparisons would otherwise put it inside any box on that axis by a
-- sequential scan but not always by the index (among 50,000 points, one of
-- NaNs only was found by a scan and missed by the index: the answer hung on
-- the plan; tests/test_gmap_multidim.py forces both plans; and NaN keys
-- spoiled the index's inner boxes, so that it missed valid points: the index
-- is partial, leaving NaN points out, and the query below carries its
-- predicate; tests/test_nan_boxes.py). A point whose
-- number of coordinates is not the G-map's (tgsis.check_md_geometry reports
-- it) is in no box either: the cube type's <@ ignores a box's axes beyond a
-- point's, its GiST index does not (the answer hung on the plan again).
-- md_vertex stored in chunks (docs/storage.md, "The points in chunks"):
-- the chunk versions whose box (tgsis.point_chunk_box, GiST-indexed) meets
-- the query's are decoded and their points tested as the rows are; the same
-- points, bit for bit (tests/test_point_chunk_box.py).
-- The visibility test below is tgsis.visible_versions' text, kept static (tests/test_visible_versions.py compares).
CREATE FUNCTION tgsis.md_vertices_in_box(p_geoid bigint, p_axes text[], p_low double precision[], p_high double precision[])
RETURNS TABLE (vrtxid bigint, coordinate double precision[])
LANGUAGE plpgsql
STABLE
SET search_path FROM CURRENT
AS $$
DECLARE
    v_box  cube;
    v_axes text[];
    v_set  integer[];  -- the session's viewing set when md_vertex is versioned (chunks: the faces' visibility test)
    v_size integer;
BEGIN
    SELECT tgsis.md_query_box(g.axes, p_axes, p_low, p_high), g.axes INTO v_box, v_axes FROM tgsis.md_gmap g WHERE g.geoid = p_geoid;
    IF NOT FOUND THEN
        RAISE EXCEPTION 'geometry % is not a stored multiply indexed G-map', p_geoid
            USING ERRCODE = 'TG200', HINT = 'SELECT geoid FROM tgsis.md_gmap lists them';
    END IF;
    IF v_box IS NULL THEN   -- the box is well formed (md_query_box checked it): an axis is not the G-map's
        RAISE EXCEPTION 'multiply indexed G-map % has no axis %', p_geoid,
                quote_literal(left((SELECT a FROM unnest(p_axes) a WHERE a <> ALL (v_axes) LIMIT 1), 100))
            USING ERRCODE = 'TG100', DETAIL = format('Its axes: %s.', array_to_string(v_axes, ', ')),
                  HINT = 'p_axes names some of the G-map''s axes (SELECT axes FROM tgsis.md_gmap WHERE geoid = ...)';
    END IF;
    -- stored in chunks: the chunk versions the session sees (the face's test) whose box meets the query's (the GiST
    -- index on tgsis.point_chunk_box: a chunk's points all have its m coordinates, and a chunk whose m is not the
    -- object's holds no answer), decoded as the face decodes them and tested as the rows are; read as the caller
    -- under the chunk table's row-level security, as tgsis.chunk_object_extent reads (the face otherwise: a role
    -- granted the face only)
    IF tgsis.stored_in_chunks('md_vertex') AND to_regclass('tgsis.md_vertex_chunk') IS NOT NULL
       AND has_table_privilege(to_regclass('tgsis.md_vertex_chunk'), 'SELECT') THEN
        IF EXISTS (SELECT FROM tgsis.versioned_tables t WHERE t.schemaname = 'tgsis' AND t.tablename = 'md_vertex') THEN
            v_set := tgsis.get_revisions(true);
        END IF;
        v_size := (SELECT r.chunksize FROM tgsis.model_tables r WHERE r.tablename = 'md_vertex');
        RETURN QUERY
        SELECT c.chunk * v_size + u.o - 1, p.flat[(u.o - 1) * p.m + 1 : u.o * p.m]
          FROM tgsis.md_vertex_chunk c
         CROSS JOIN LATERAL (SELECT ARRAY(SELECT coalesce(x, 0) FROM unnest(c.coordinate) AS x) AS flat,
                                    array_length(c.coordinate, 2) AS m OFFSET 0) p
         CROSS JOIN LATERAL unnest(c.coordinate[:][1:1]) WITH ORDINALITY AS u(first, o)
         WHERE (SELECT tgsis.chunk_snapshot_guard('tgsis.md_vertex_chunk'::regclass))
           AND c.geoid = p_geoid
           AND tgsis.point_chunk_box(c.coordinate) && v_box
           AND p.m = cardinality(v_axes)
           AND (v_set IS NULL OR ((c.revision = ANY (v_set)) IS TRUE AND (NOT c.revclosed OR NOT (c.lastrevs && v_set))))
           AND u.first IS NOT NULL
           AND cube(p.flat[(u.o - 1) * p.m + 1 : u.o * p.m]) <@ v_box
           AND NOT 'NaN'::double precision = ANY (p.flat[(u.o - 1) * p.m + 1 : u.o * p.m])
         ORDER BY 1;
        RETURN;
    END IF;
    RETURN QUERY
    SELECT v.vrtxid, v.coordinate FROM tgsis.md_vertex v
     WHERE cube(v.coordinate) <@ v_box AND v.geoid = p_geoid
       AND NOT 'NaN'::double precision = ANY (v.coordinate)  -- NaN = NaN for float8's equality
       AND cardinality(v.coordinate) = cardinality(v_axes)
     ORDER BY v.vrtxid;
END
$$;

COMMENT ON FUNCTION tgsis.md_vertices_in_box(bigint, text[], double precision[], double precision[]) IS
    'model 5: the points (vrtxid, coordinate) of a multiply indexed G-map inside a box over some of its axes (unbounded on the others, closed: a point on a face is inside; a point with a NaN coordinate is in none), by GiST index (on the points, or on each chunk''s box when md_vertex is stored in chunks); a point of other than the G-map''s number of coordinates is in none';
