-- tgsis.add_instant(geoid, t): record a new instant of a model-2 surface; the caller then stores its vertices, triangles and properties there.
CREATE FUNCTION tgsis.add_instant(p_geoid bigint, p_t double precision)
RETURNS void
LANGUAGE plpgsql
SET extra_float_digits = 1  -- its messages name instants exactly, whatever the session's setting
AS $$
BEGIN
    PERFORM tgsis.plain_write_check('tgsis', 'times');  -- not "in" a version while features are plain
    PERFORM tgsis.temporal_geometry(p_geoid, 'INSTANTS');
    IF p_t IS NULL OR p_t IN ('NaN', 'Infinity', '-Infinity') THEN
        RAISE EXCEPTION 'instant % of geometry % must be a finite number', coalesce(p_t::text, 'NULL'), p_geoid
            USING ERRCODE = 'TG100';
    END IF;
    IF EXISTS (SELECT FROM tgsis.times WHERE geoid = p_geoid AND times = p_t) THEN
        RAISE EXCEPTION 'geometry % has an instant % already', p_geoid, p_t
            USING ERRCODE = 'TG201', HINT = 'tgsis.delete_instant removes it first';
    END IF;
    INSERT INTO tgsis.times (geoid, times) VALUES (p_geoid, p_t);
END
$$;

COMMENT ON FUNCTION tgsis.add_instant(bigint, double precision) IS
    'model 2: add instant t to a surface (TG201 if it has it already); its vertices, triangles and properties are stored next in the same transaction';
