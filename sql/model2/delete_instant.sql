-- tgsis.delete_instant(geoid, t): remove one instant of a model-2 surface with its vertices, triangles and properties.
-- Refuses (TG202) the only instant: that is deleting the feature. A time
-- table stored in chunks loses the instant's chunk versions whole
-- (tgsis.delete_chunk_slice: the face's checks, one statement), not a chunk
-- rewrite per row through the face; the class's property tables stay rows.
CREATE FUNCTION tgsis.delete_instant(p_geoid bigint, p_t double precision)
RETURNS boolean
LANGUAGE plpgsql
SET extra_float_digits = 1  -- its messages name instants exactly, whatever the session's setting
AS $$
DECLARE
    v_class tgsis.catalog;
BEGIN
    PERFORM tgsis.plain_write_check('tgsis', 'times');  -- not "in" a version while features are plain
    PERFORM tgsis.temporal_geometry(p_geoid, 'INSTANTS');
    IF NOT EXISTS (SELECT FROM tgsis.times WHERE geoid = p_geoid AND times = p_t) THEN
        RETURN false;
    END IF;
    IF NOT EXISTS (SELECT FROM tgsis.times WHERE geoid = p_geoid AND times <> p_t) THEN
        RAISE EXCEPTION 'instant % is the only one of geometry %', p_t, p_geoid
            USING ERRCODE = 'TG202', HINT = format('SELECT tgsis.delete_geometry(%s) deletes the feature', p_geoid);
    END IF;
    FOR v_class IN SELECT * FROM tgsis.catalog WHERE timemodel = 'INSTANTS' LOOP
        EXECUTE format('DELETE FROM %I.%I WHERE _geoid = $1 AND _times = $2', v_class.schemaname, v_class.cellprotable)
          USING p_geoid, p_t;
        EXECUTE format('DELETE FROM %I.%I WHERE _geoid = $1 AND _times = $2', v_class.schemaname, v_class.protablename)
          USING p_geoid, p_t;
    END LOOP;
    -- a time table in chunks: the instant's chunk versions closed whole (not a chunk rewrite per row)
    IF tgsis.stored_in_chunks('times_trgl') THEN
        PERFORM tgsis.delete_chunk_slice('times_trgl', p_geoid, ARRAY[p_t]);
    ELSE
        DELETE FROM tgsis.times_trgl WHERE geoid = p_geoid AND times = p_t;
    END IF;
    IF tgsis.stored_in_chunks('times_vrtx') THEN
        PERFORM tgsis.delete_chunk_slice('times_vrtx', p_geoid, ARRAY[p_t]);
    ELSE
        DELETE FROM tgsis.times_vrtx WHERE geoid = p_geoid AND times = p_t;
    END IF;
    DELETE FROM tgsis.times WHERE geoid = p_geoid AND times = p_t;
    PERFORM tgsis.refresh_geometry(p_geoid);
    RETURN true;
END
$$;

COMMENT ON FUNCTION tgsis.delete_instant(bigint, double precision) IS
    'model 2: delete instant t of a surface with its vertices, triangles and per-instant and cell properties, in the session''s version; false if it had no such instant; TG202 for its only instant';
