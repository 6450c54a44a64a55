-- tgsis.evolving_chunk_vertices(geoid, timem, t0, t1, w): model 3's node positions at t read from the chunks' arrays.
-- docs/storage.md, "Snapshots at t (models 2 and 3)": once tgsis.d4dvrtx is
-- stored in chunks, the node-id -> chunk mapping is the same at every geometry
-- instant of a period, so chunk k of t0 and chunk k of t1 hold the same nodes
-- slot by slot. tgsis.vertices_at calls this with its frame (tgsis.evolving_frame)
-- instead of joining two instants of the face: the visible chunk versions of the
-- two instants (tgsis.d4dvrtx_arrays, the view the switch makes with the face's
-- guard, visibility, class rights filter and grants) are joined on their chunk
-- and their arrays unnested side by side; a slot present at both instants
-- (neither x NULL: a hole or a node one instant lacks is left out, as the rows'
-- join leaves it out) gives the node base + o - 1 at a.x + w (b.x - a.x), the
-- operations of the rows' path in the same order (the same bits). At a
-- geometry instant (t0 = t1) the stored positions of t0's chunks. Nothing for a
-- NULL frame (not model 3, or not existing at t). Runs as its caller (the
-- view's grants decide), static SQL: the view exists only while tgsis.d4dvrtx is
-- in chunks, and tgsis.vertices_at calls this only then.
CREATE FUNCTION tgsis.evolving_chunk_vertices(p_geoid bigint, p_timem double precision, p_t0 double precision,
                                              p_t1 double precision, p_w double precision)
RETURNS TABLE (vrtxid bigint, x double precision, y double precision, z double precision)
LANGUAGE plpgsql
STABLE
PARALLEL SAFE  -- reads only; tgsis.vertices_at, which calls it, is PARALLEL SAFE
SET search_path = pg_catalog, pg_temp
AS $$
BEGIN
    IF p_t0 = p_t1 THEN
        RETURN QUERY
            SELECT a.base + (u.o - 1), u.x, u.y, u.z
              FROM tgsis.d4dvrtx_arrays a
             CROSS JOIN LATERAL unnest(a.x, a.y, a.z) WITH ORDINALITY AS u(x, y, z, o)
             WHERE a.geoid = p_geoid AND a.timem = p_timem AND a.timet = p_t0 AND u.x IS NOT NULL;
    ELSIF p_t0 < p_t1 THEN
        RETURN QUERY
            SELECT a.base + (u.o - 1), u.ax + p_w * (u.bx - u.ax), u.ay + p_w * (u.by - u.ay), u.az + p_w * (u.bz - u.az)
              FROM tgsis.d4dvrtx_arrays a
              JOIN tgsis.d4dvrtx_arrays b ON b.geoid = a.geoid AND b.timem = a.timem AND b.chunk = a.chunk
             CROSS JOIN LATERAL unnest(a.x, a.y, a.z, b.x, b.y, b.z) WITH ORDINALITY AS u(ax, ay, az, bx, by, bz, o)
             WHERE a.geoid = p_geoid AND a.timem = p_timem AND a.timet = p_t0
               AND b.geoid = p_geoid AND b.timem = p_timem AND b.timet = p_t1
               AND u.ax IS NOT NULL AND u.bx IS NOT NULL;
    END IF;
END
$$;

-- executable by PUBLIC, as tgsis.vertices_at is: the executor checks EXECUTE on every function a query names when
-- it starts the query, whether the branch that calls it runs or not (a role outside tgsis_reader calling
-- vertices_at was refused 42501 on rows too); it runs as its caller, who reads the view only with its own rights

COMMENT ON FUNCTION tgsis.evolving_chunk_vertices(bigint, double precision, double precision, double precision, double precision) IS
    'model 3''s node positions (vrtxid, x, y, z) in period timem at the frame (t0, t1, w) of tgsis.evolving_frame, read from the aligned chunk arrays of tgsis.d4dvrtx_arrays (t0 = t1: the stored positions; t0 < t1: x0 + w (x1 - x0) per slot present at both, the bits of the rows'' join); called by tgsis.vertices_at while tgsis.d4dvrtx is stored in chunks and the caller may read that view';
