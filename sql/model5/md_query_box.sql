-- tgsis.md_query_box(axes of the object, axes asked, low, high): the m-dimensional cube of a box over some of an object's axes.
-- A box over a subset of the dimensions is the cube that is unbounded
-- (-Infinity .. Infinity) on every other axis, so that one GiST index on the
-- full extents (or points) serves a query over any subset. NULL when the
-- object lacks one of the asked axes (it cannot be in the box).
CREATE FUNCTION tgsis.md_query_box(p_object_axes text[], p_axes text[], p_low double precision[],
                                   p_high double precision[])
RETURNS cube
LANGUAGE plpgsql
IMMUTABLE
PARALLEL SAFE
SET search_path FROM CURRENT
AS $$
DECLARE
    v_low  double precision[] := array_fill('-Infinity'::double precision, ARRAY[cardinality(p_object_axes)]);
    v_high double precision[] := array_fill('Infinity'::double precision, ARRAY[cardinality(p_object_axes)]);
    v_at   integer;
BEGIN
    IF p_axes IS NULL OR cardinality(p_axes) = 0 OR cardinality(p_low) IS DISTINCT FROM cardinality(p_axes)
       OR cardinality(p_high) IS DISTINCT FROM cardinality(p_axes) THEN
        RAISE EXCEPTION 'a box names at least one axis and gives one low and one high value per axis, got axes %, low %, high %',
                        p_axes, p_low, p_high
            USING ERRCODE = 'TG100', HINT = 'p_axes => ''{x,knowledge}'', p_low => ''{0,1}'', p_high => ''{10,2}''';
    END IF;
    FOR i IN 1 .. cardinality(p_axes) LOOP
        IF p_low[i] IS NULL OR p_high[i] IS NULL OR p_low[i] = 'NaN' OR p_high[i] = 'NaN' OR p_low[i] > p_high[i] THEN
            RAISE EXCEPTION 'the box over axis % must have low <= high, got % .. %', quote_literal(p_axes[i]), p_low[i], p_high[i]
                USING ERRCODE = 'TG100';
        END IF;
        v_at := array_position(p_object_axes, p_axes[i]);
        IF v_at IS NULL THEN
            RETURN NULL;
        END IF;
        v_low[v_at] := greatest(v_low[v_at], p_low[i]);
        v_high[v_at] := least(v_high[v_at], p_high[i]);
    END LOOP;
    RETURN cube(v_low, v_high);
END
$$;

COMMENT ON FUNCTION tgsis.md_query_box(text[], text[], double precision[], double precision[]) IS
    'model 5: the cube over an object''s axes of a box given on some of them (unbounded on the others); NULL when the object lacks an asked axis; TG100 for a malformed box';
