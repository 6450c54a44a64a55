-- tgsis.surfaces_at(class, t, convention): every feature of a class that exists at t with its surface then, as arrays.
-- vertices is n x 3 (x, y, z, in vertex-id order); triangles is m x 3 and
-- holds 0-based positions in vertices, so each row is a mesh by itself.
CREATE FUNCTION tgsis.surfaces_at(p_class text, p_t double precision, p_convention text DEFAULT 'left')
RETURNS TABLE (geoid bigint, vertices double precision[], triangles bigint[])
LANGUAGE plpgsql
STABLE
-- vertices_at/triangles_at inlined per feature are costed far above jit_above_cost: with JIT (Debian's
-- PostgreSQL 15) every call compiled the query, 2.6 s for a small scene that runs in ms (as the Python snapshot)
SET jit = off
AS $$
DECLARE
    v_class tgsis.catalog := tgsis.catalog_row(p_class);
BEGIN
    IF v_class.geotype <> 'SURFACE' THEN
        RAISE EXCEPTION 'feature class % holds % features, not surfaces', p_class, v_class.geotype
            USING ERRCODE = 'TG100', HINT = 'tgsis.features_at lists the features of any class that exist at t';
    END IF;
    PERFORM tgsis.checked_time(p_t), tgsis.checked_convention(p_convention);
    RETURN QUERY EXECUTE format($q$
        WITH f AS (
            SELECT _geoid AS geoid FROM %I.%I WHERE tgsis.exists_at(_geoid, $1, $2)
        ), v AS (
            SELECT f.geoid, v.vrtxid, v.x, v.y, v.z, row_number() OVER (PARTITION BY f.geoid ORDER BY v.vrtxid) - 1 AS pos
              FROM f, tgsis.vertices_at(f.geoid, $1, $2) v
        ), c AS (
            SELECT f.geoid, c.trglid, p1.pos AS pos1, p2.pos AS pos2, p3.pos AS pos3
              FROM f
             CROSS JOIN LATERAL tgsis.triangles_at(f.geoid, $1, $2) c
              JOIN v p1 ON p1.geoid = f.geoid AND p1.vrtxid = c.vrtxid1
              JOIN v p2 ON p2.geoid = f.geoid AND p2.vrtxid = c.vrtxid2
              JOIN v p3 ON p3.geoid = f.geoid AND p3.vrtxid = c.vrtxid3
        )
        SELECT f.geoid,
               (SELECT array_agg(ARRAY[v.x, v.y, v.z] ORDER BY v.pos) FROM v WHERE v.geoid = f.geoid),
               (SELECT array_agg(ARRAY[c.pos1, c.pos2, c.pos3] ORDER BY c.trglid) FROM c WHERE c.geoid = f.geoid)
          FROM f
         ORDER BY f.geoid
        $q$, v_class.schemaname, v_class.featuretable)
        USING p_t, p_convention;
END
$$;

COMMENT ON FUNCTION tgsis.surfaces_at(text, double precision, text) IS
    'every feature of a SURFACE class that exists at model time t with its shape then: vertices (n x 3 array) and triangles (m x 3 array of 0-based positions in vertices)';
