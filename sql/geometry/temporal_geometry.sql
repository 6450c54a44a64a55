-- tgsis.temporal_geometry(geoid, time model): lock and check a geometry of that time model; TG200 / TG100 naming it otherwise.
CREATE FUNCTION tgsis.temporal_geometry(p_geoid bigint, p_time_model text)
RETURNS void
LANGUAGE plpgsql
AS $$
DECLARE
    v_model text;
BEGIN
    SELECT timemodel INTO v_model FROM tgsis.geometry WHERE geoid = p_geoid FOR UPDATE;
    IF NOT FOUND THEN
        RAISE EXCEPTION 'geometry % does not exist', p_geoid
            USING ERRCODE = 'TG200', HINT = 'SELECT geoid FROM tgsis.geometry lists the stored geometries';
    ELSIF v_model <> p_time_model THEN
        RAISE EXCEPTION 'geometry % has time model %, not %', p_geoid, v_model, p_time_model
            USING ERRCODE = 'TG100',
                  HINT = 'instants are added to and deleted from surfaces of INSTANTS classes (model 2)';
    END IF;
END
$$;

COMMENT ON FUNCTION tgsis.temporal_geometry(bigint, text) IS
    'lock a geometry row and check its time model (TG200 if it does not exist, TG100 if its time model differs)';
