-- tgsis.gap_tolerance(geoid, tolerance): the largest gap a topology change of a model-3 or model-4 geometry may have.
-- The design requires the shape just before a topology instant and just
-- after it to be the same (pre- and post-object share their geometry);
-- coordinates computed by different programs agree only up to rounding, so
-- "the same" is "within a tolerance". In order: the argument when given;
-- else the session's setting tgsis.period_tolerance (SET tgsis.period_tolerance TO
-- '0.01', in model units); else one millionth of the diagonal of the
-- geometry's bounding box over all its instants (1 mm for a 1 km model).
-- A tolerance is finite and >= 0.
CREATE FUNCTION tgsis.gap_tolerance(p_geoid bigint, p_tolerance double precision DEFAULT NULL)
RETURNS double precision
LANGUAGE plpgsql
STABLE
SET search_path FROM CURRENT
AS $$
DECLARE
    v_setting text;
    v_value   double precision;
    v_bbox    cube;
BEGIN
    IF p_tolerance IS NOT NULL THEN
        v_value := p_tolerance;
        v_setting := 'the tolerance argument';
    ELSE
        v_setting := nullif(btrim(current_setting('tgsis.period_tolerance', true)), '');
        IF v_setting IS NOT NULL THEN
            BEGIN
                v_value := v_setting::double precision;
            EXCEPTION WHEN invalid_text_representation THEN
                RAISE EXCEPTION 'the setting tgsis.period_tolerance (%) is no number', v_setting
                    USING ERRCODE = 'TG100', HINT = 'a distance in model units, e.g. SET tgsis.period_tolerance TO ''0.01''; RESET tgsis.period_tolerance takes the default';
            END;
            v_setting := format('the setting tgsis.period_tolerance (%s)', v_setting);
        END IF;
    END IF;
    IF v_value IS NOT NULL THEN
        IF v_value < 0 OR v_value = 'Infinity' OR v_value = 'NaN' THEN
            RAISE EXCEPTION 'a tolerance of topology changes must be a finite distance >= 0, % is %', v_setting, v_value
                USING ERRCODE = 'TG100', HINT = 'a distance in model units, e.g. 0.01';
        END IF;
        RETURN v_value;
    END IF;
    SELECT g.bbox INTO v_bbox FROM tgsis.geometry g WHERE g.geoid = p_geoid;
    IF v_bbox IS NULL THEN
        RETURN 0;
    END IF;
    RETURN 1e-6 * sqrt((SELECT sum((cube_ur_coord(v_bbox, i) - cube_ll_coord(v_bbox, i)) ^ 2)
                          FROM generate_series(1, cube_dim(v_bbox)) i));
END
$$;

COMMENT ON FUNCTION tgsis.gap_tolerance(bigint, double precision) IS
    'the largest gap allowed between the shapes before and after a topology instant of a model-3 or model-4 geometry: the argument, else the setting tgsis.period_tolerance, else 1e-6 times the diagonal of the geometry''s bounding box; TG100 for a negative, infinite or non-numeric one';
