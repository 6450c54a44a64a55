-- tgsis.point_chunk_box(points): the box of a chunk of points (a G-map's vertices in chunks, role 'point'), the key of its GiST index.
-- docs/storage.md, "The points in chunks": a point chunk is a 2-D double
-- precision[] (slots x m, a hole a row of m NULLs). Its box is the cube of m
-- dimensions from the least to the greatest coordinate per axis over the
-- points that have a position: a hole, and a point with a NaN coordinate
-- (in no box: tgsis.md_vertices_in_box), are left out; NULL when no point is
-- left (such a chunk is in no box and no box query reads it) or m > 100 (the
-- cube type's limit). Computed from the chunk itself, never written by a
-- writer: tgsis.create_chunk_table indexes it as an expression
-- (<table>_chunk_<column>_box_idx), so every writer of chunks (the server's,
-- the client's COPY, the face, the merges, the conversion) keeps it right by
-- construction. Executable by PUBLIC: the index's expression, evaluated by
-- whoever writes the chunks, and tgsis.md_vertices_in_box's filter, run as
-- the caller.
CREATE FUNCTION tgsis.point_chunk_box(p_points double precision[])
RETURNS cube
LANGUAGE plpgsql
IMMUTABLE
STRICT
PARALLEL SAFE
COST 10000  -- a pass over 1,024 points (~1 ms): the planner reads the box index rather than computing it per chunk
SET search_path FROM CURRENT
AS $$
DECLARE
    v_m     integer := array_length(p_points, 2);
    v_lo    double precision[];
    v_hi    double precision[];
    v_point double precision[];
    v_x     double precision;
    v_i     integer := 0;
    v_k     integer;
    v_ok    boolean := true;
    v_any   boolean := false;
BEGIN
    IF array_ndims(p_points) IS DISTINCT FROM 2 OR v_m > 100 THEN
        RETURN NULL;
    END IF;
    v_lo := array_fill(NULL::double precision, ARRAY[v_m]);
    v_hi := v_lo;
    v_point := v_lo;
    -- one pass over the elements in storage order (slot by slot, its m coordinates in a row; a set-returning SQL form
    -- of this, unnest WITH ORDINALITY grouped by axis, cost about 20 times more per chunk)
    IF ('NaN'::double precision = ANY (p_points)) IS FALSE THEN   -- no NaN and no NULL (a hole): every point counts
        FOREACH v_x IN ARRAY p_points LOOP
            v_k := v_i % v_m + 1;
            v_i := v_i + 1;
            v_lo[v_k] := least(v_lo[v_k], v_x);   -- least and greatest skip the NULL of the start
            v_hi[v_k] := greatest(v_hi[v_k], v_x);
        END LOOP;
        RETURN cube(v_lo, v_hi);
    END IF;
    FOREACH v_x IN ARRAY p_points LOOP
        v_k := v_i % v_m + 1;
        v_i := v_i + 1;
        v_point[v_k] := v_x;
        IF v_x IS NULL OR v_x = 'NaN' THEN   -- NaN = NaN for float8's equality
            v_ok := false;
        END IF;
        IF v_k = v_m THEN
            IF v_ok THEN
                FOR v_k IN 1 .. v_m LOOP
                    v_lo[v_k] := least(v_lo[v_k], v_point[v_k]);
                    v_hi[v_k] := greatest(v_hi[v_k], v_point[v_k]);
                END LOOP;
                v_any := true;
            END IF;
            v_ok := true;
        END IF;
    END LOOP;
    RETURN CASE WHEN v_any THEN cube(v_lo, v_hi) END;
END
$$;

COMMENT ON FUNCTION tgsis.point_chunk_box(double precision[]) IS
    'the box (cube of m dimensions) of a chunk of points (slots x m): least and greatest coordinate per axis over the points without a NULL or NaN coordinate; NULL when none is left or m > 100; the expression of the point chunk tables'' box index (tgsis.create_chunk_table), read by tgsis.md_vertices_in_box';
