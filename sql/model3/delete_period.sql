-- tgsis.delete_period(geoid, timem): remove the first or the last topology period of a model-3 surface, with its nodes, triangles, positions and properties.
-- The periods of an evolving surface follow each other (each ends where the
-- next starts), so only an end period can go: a middle one would leave a
-- gap (TG202), and the only one is the whole feature (TG202). With the last
-- period gone the surface ends at the last geometry instant of the one
-- before (alive or not as before); with the first gone it starts where the
-- second starts. Returns false when no period starts at timem. A time
-- table stored in chunks (d4dvrtx, d4dtrgl) loses the period's chunk versions
-- whole (tgsis.delete_chunk_slice), not a chunk rewrite per row.
CREATE FUNCTION tgsis.delete_period(p_geoid bigint, p_timem double precision)
RETURNS boolean
LANGUAGE plpgsql
SET extra_float_digits = 1  -- its messages name instants exactly, whatever the session's setting
AS $$
DECLARE
    v_first double precision;
    v_last  double precision;
    v_count bigint;
    v_class tgsis.catalog;
BEGIN
    PERFORM tgsis.plain_write_check('tgsis', 'timem');  -- not "in" a version while features are plain
    PERFORM tgsis.temporal_geometry(p_geoid, 'EVOLVING');
    -- one writer of the feature's periods at a time (tgsis.append_period locks the same row)
    PERFORM FROM tgsis.geometry WHERE geoid = p_geoid FOR UPDATE;
    IF NOT EXISTS (SELECT FROM tgsis.timem WHERE geoid = p_geoid AND timem = p_timem) THEN
        RETURN false;
    END IF;
    SELECT min(timem), max(timem), count(*) INTO v_first, v_last, v_count FROM tgsis.timem WHERE geoid = p_geoid;
    IF v_count = 1 THEN
        RAISE EXCEPTION 'the topology period from % is the only one of geometry %', p_timem, p_geoid
            USING ERRCODE = 'TG202', HINT = format('SELECT tgsis.delete_geometry(%s) deletes the feature', p_geoid);
    END IF;
    IF p_timem <> v_first AND p_timem <> v_last THEN
        RAISE EXCEPTION 'the topology period from % of geometry % lies between others: removing it would leave a gap',
                p_timem, p_geoid
            USING ERRCODE = 'TG202',
                  DETAIL = format('Its periods start at %s; each ends where the next starts.',
                                  (SELECT string_agg(timem::text, ', ' ORDER BY timem) FROM tgsis.timem WHERE geoid = p_geoid)),
                  HINT = 'remove the first or the last period';
    END IF;
    FOR v_class IN SELECT * FROM tgsis.catalog WHERE timemodel = 'EVOLVING' LOOP
        EXECUTE format('DELETE FROM %I.%I WHERE _geoid = $1 AND _timem = $2', v_class.schemaname, v_class.cellprotable)
          USING p_geoid, p_timem;
        EXECUTE format('DELETE FROM %I.%I WHERE _geoid = $1 AND _timem = $2', v_class.schemaname, v_class.protablename)
          USING p_geoid, p_timem;
    END LOOP;
    -- a time table in chunks: the period's chunk versions closed whole (not a chunk rewrite per row)
    IF tgsis.stored_in_chunks('d4dvrtx') THEN
        PERFORM tgsis.delete_chunk_slice('d4dvrtx', p_geoid, ARRAY[p_timem]);
    ELSE
        DELETE FROM tgsis.d4dvrtx WHERE geoid = p_geoid AND timem = p_timem;
    END IF;
    IF tgsis.stored_in_chunks('d4dtrgl') THEN
        PERFORM tgsis.delete_chunk_slice('d4dtrgl', p_geoid, ARRAY[p_timem]);
    ELSE
        DELETE FROM tgsis.d4dtrgl WHERE geoid = p_geoid AND timem = p_timem;
    END IF;
    DELETE FROM tgsis.node WHERE geoid = p_geoid AND timem = p_timem;
    DELETE FROM tgsis.timet WHERE geoid = p_geoid AND timem = p_timem;
    DELETE FROM tgsis.timem WHERE geoid = p_geoid AND timem = p_timem;
    PERFORM tgsis.refresh_geometry(p_geoid);
    RETURN true;
END
$$;

COMMENT ON FUNCTION tgsis.delete_period(bigint, double precision) IS
    'model 3: delete the first or last topology period (starting at timem) of an evolving surface with its nodes, triangles, positions and properties, in the session''s version; false if no period starts there; TG202 for the only period or one between others';
