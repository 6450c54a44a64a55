-- tgsis.delete_geometry(geoid): remove a geometry with its vertices, simplices, feature row and cell properties.
CREATE FUNCTION tgsis.delete_geometry(p_geoid bigint)
RETURNS boolean
LANGUAGE plpgsql
AS $$
DECLARE
    v_geotype text;
    v_class   record;
BEGIN
    SELECT geotype INTO v_geotype FROM tgsis.geometry WHERE geoid = p_geoid FOR UPDATE;
    IF NOT FOUND THEN
        RETURN false;
    END IF;
    -- cell properties have no foreign key (bulk upload speed): remove them by class
    FOR v_class IN SELECT schemaname, cellprotable FROM tgsis.catalog WHERE geotype = v_geotype LOOP
        EXECUTE format('DELETE FROM %I.%I WHERE _geoid = $1', v_class.schemaname, v_class.cellprotable) USING p_geoid;
    END LOOP;
    DELETE FROM tgsis.vrtx WHERE geoid = p_geoid;
    IF v_geotype <> 'GEOMETRYCOLLECTION' THEN
        EXECUTE format('DELETE FROM tgsis.%I WHERE geoid = $1', tgsis.simplex_table(v_geotype)) USING p_geoid;
    END IF;
    DELETE FROM tgsis.geometry WHERE geoid = p_geoid;  -- the feature row goes with it (ON DELETE CASCADE)
    RETURN true;
END
$$;

COMMENT ON FUNCTION tgsis.delete_geometry(bigint) IS
    'delete a geometry, its vertices, simplices, feature row and cell properties; false if it did not exist';
