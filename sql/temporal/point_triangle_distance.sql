-- tgsis.point_triangle_distance(p, a, b, c): Euclidean distance from a point to a triangle in 3D (all as x, y, z).
-- Why: the continuity check of topology changes (tgsis.period_gaps) measures
-- how far each vertex of the object after a topology instant lies from the
-- surface before it, and the other way round. The closest point is found by
-- the Voronoi regions of the triangle (Ericson, Real-Time Collision
-- Detection, 5.1.5); a degenerate triangle (collinear or coincident corners)
-- is measured as its three edges.
CREATE FUNCTION tgsis.point_triangle_distance(
    p_x double precision, p_y double precision, p_z double precision,
    p_ax double precision, p_ay double precision, p_az double precision,
    p_bx double precision, p_by double precision, p_bz double precision,
    p_cx double precision, p_cy double precision, p_cz double precision)
RETURNS double precision
LANGUAGE plpgsql
IMMUTABLE STRICT PARALLEL SAFE
AS $$
DECLARE
    v_abx double precision := p_bx - p_ax;  v_aby double precision := p_by - p_ay;  v_abz double precision := p_bz - p_az;
    v_acx double precision := p_cx - p_ax;  v_acy double precision := p_cy - p_ay;  v_acz double precision := p_cz - p_az;
    v_apx double precision := p_x - p_ax;   v_apy double precision := p_y - p_ay;   v_apz double precision := p_z - p_az;
    v_d1 double precision; v_d2 double precision; v_d3 double precision; v_d4 double precision;
    v_d5 double precision; v_d6 double precision;
    v_va double precision; v_vb double precision; v_vc double precision;
    v_v double precision; v_w double precision; v_sum double precision;
    v_qx double precision; v_qy double precision; v_qz double precision;
BEGIN
    v_d1 := v_abx * v_apx + v_aby * v_apy + v_abz * v_apz;
    v_d2 := v_acx * v_apx + v_acy * v_apy + v_acz * v_apz;
    IF v_d1 <= 0 AND v_d2 <= 0 THEN                                   -- corner a
        RETURN sqrt(v_apx * v_apx + v_apy * v_apy + v_apz * v_apz);
    END IF;
    v_d3 := v_abx * (p_x - p_bx) + v_aby * (p_y - p_by) + v_abz * (p_z - p_bz);
    v_d4 := v_acx * (p_x - p_bx) + v_acy * (p_y - p_by) + v_acz * (p_z - p_bz);
    IF v_d3 >= 0 AND v_d4 <= v_d3 THEN                                -- corner b
        RETURN sqrt((p_x - p_bx) ^ 2 + (p_y - p_by) ^ 2 + (p_z - p_bz) ^ 2);
    END IF;
    v_d5 := v_abx * (p_x - p_cx) + v_aby * (p_y - p_cy) + v_abz * (p_z - p_cz);
    v_d6 := v_acx * (p_x - p_cx) + v_acy * (p_y - p_cy) + v_acz * (p_z - p_cz);
    IF v_d6 >= 0 AND v_d5 <= v_d6 THEN                                -- corner c
        RETURN sqrt((p_x - p_cx) ^ 2 + (p_y - p_cy) ^ 2 + (p_z - p_cz) ^ 2);
    END IF;
    v_vc := v_d1 * v_d4 - v_d3 * v_d2;
    v_vb := v_d5 * v_d2 - v_d1 * v_d6;
    v_va := v_d3 * v_d6 - v_d5 * v_d4;
    v_sum := v_va + v_vb + v_vc;
    IF v_sum <= 0 THEN                                                -- degenerate: the nearest of the three edges
        RETURN least(tgsis.point_segment_distance(ARRAY[p_x, p_y, p_z], ARRAY[p_ax, p_ay, p_az], ARRAY[p_bx, p_by, p_bz]),
                     tgsis.point_segment_distance(ARRAY[p_x, p_y, p_z], ARRAY[p_bx, p_by, p_bz], ARRAY[p_cx, p_cy, p_cz]),
                     tgsis.point_segment_distance(ARRAY[p_x, p_y, p_z], ARRAY[p_cx, p_cy, p_cz], ARRAY[p_ax, p_ay, p_az]));
    END IF;
    IF v_vc <= 0 AND v_d1 >= 0 AND v_d3 <= 0 THEN                     -- edge ab
        v_v := v_d1 / (v_d1 - v_d3);
        v_qx := p_ax + v_v * v_abx; v_qy := p_ay + v_v * v_aby; v_qz := p_az + v_v * v_abz;
    ELSIF v_vb <= 0 AND v_d2 >= 0 AND v_d6 <= 0 THEN                  -- edge ac
        v_w := v_d2 / (v_d2 - v_d6);
        v_qx := p_ax + v_w * v_acx; v_qy := p_ay + v_w * v_acy; v_qz := p_az + v_w * v_acz;
    ELSIF v_va <= 0 AND (v_d4 - v_d3) >= 0 AND (v_d5 - v_d6) >= 0 THEN  -- edge bc
        v_w := (v_d4 - v_d3) / ((v_d4 - v_d3) + (v_d5 - v_d6));
        v_qx := p_bx + v_w * (p_cx - p_bx); v_qy := p_by + v_w * (p_cy - p_by); v_qz := p_bz + v_w * (p_cz - p_bz);
    ELSE                                                              -- inside the face
        v_v := v_vb / v_sum;
        v_w := v_vc / v_sum;
        v_qx := p_ax + v_v * v_abx + v_w * v_acx;
        v_qy := p_ay + v_v * v_aby + v_w * v_acy;
        v_qz := p_az + v_v * v_abz + v_w * v_acz;
    END IF;
    RETURN sqrt((p_x - v_qx) ^ 2 + (p_y - v_qy) ^ 2 + (p_z - v_qz) ^ 2);
END
$$;

COMMENT ON FUNCTION tgsis.point_triangle_distance(double precision, double precision, double precision, double precision,
                                                  double precision, double precision, double precision, double precision,
                                                  double precision, double precision, double precision, double precision) IS
    'Euclidean distance from point (x, y, z) to the triangle a, b, c in 3D (a degenerate triangle: to its edges); used by tgsis.period_gaps';
