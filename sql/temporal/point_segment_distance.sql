-- tgsis.point_segment_distance(p, a, b): Euclidean distance in R^m from a point to the segment a-b (arrays of m coordinates).
-- Why: the continuity check of topology changes of G-maps (model 4, points
-- in R^m) measures how far each point of the object after a topology
-- instant lies from the edges of the object before it (tgsis.period_gaps);
-- a segment whose ends coincide is its point. Arrays of different lengths
-- are compared on their common coordinates after padding with zeros.
CREATE FUNCTION tgsis.point_segment_distance(p_p double precision[], p_a double precision[], p_b double precision[])
RETURNS double precision
LANGUAGE plpgsql
IMMUTABLE STRICT PARALLEL SAFE
AS $$
DECLARE
    v_m   int := greatest(cardinality(p_p), cardinality(p_a), cardinality(p_b));
    v_ab  double precision := 0;
    v_ap  double precision := 0;
    v_s   double precision;
    v_d   double precision := 0;
    v_i   int;
BEGIN
    FOR v_i IN 1 .. v_m LOOP
        v_ab := v_ab + (coalesce(p_b[v_i], 0) - coalesce(p_a[v_i], 0)) ^ 2;
        v_ap := v_ap + (coalesce(p_b[v_i], 0) - coalesce(p_a[v_i], 0)) * (coalesce(p_p[v_i], 0) - coalesce(p_a[v_i], 0));
    END LOOP;
    v_s := CASE WHEN v_ab > 0 THEN least(greatest(v_ap / v_ab, 0), 1) ELSE 0 END;
    FOR v_i IN 1 .. v_m LOOP
        v_d := v_d + (coalesce(p_p[v_i], 0) - (coalesce(p_a[v_i], 0) + v_s * (coalesce(p_b[v_i], 0) - coalesce(p_a[v_i], 0)))) ^ 2;
    END LOOP;
    RETURN sqrt(v_d);
END
$$;

COMMENT ON FUNCTION tgsis.point_segment_distance(double precision[], double precision[], double precision[]) IS
    'Euclidean distance in R^m from point p to the segment a-b (a point when a = b); used by tgsis.period_gaps and tgsis.point_triangle_distance';
