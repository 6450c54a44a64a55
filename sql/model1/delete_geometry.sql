-- tgsis.delete_geometry(geoid): remove a geometry with its vertices, simplices, feature row and cell properties.
-- Works in the session's version: on versioned tables the rows are closed
-- set-based (tgsis.delete_object_rows), not one trigger call per vertex.
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
    -- cell properties and feature rows: the feature table's foreign key is
    -- gone once model 1 is versioned, so delete them explicitly
    FOR v_class IN SELECT schemaname, featuretable, cellprotable FROM tgsis.catalog WHERE geotype = v_geotype LOOP
        PERFORM tgsis.delete_object_rows(v_class.schemaname, v_class.cellprotable, '_geoid', p_geoid);
        PERFORM tgsis.delete_object_rows(v_class.schemaname, v_class.featuretable, '_geoid', p_geoid);
    END LOOP;
    PERFORM tgsis.delete_object_rows('tgsis', 'vrtx', 'geoid', p_geoid);
    IF v_geotype <> 'GEOMETRYCOLLECTION' THEN
        PERFORM tgsis.delete_object_rows('tgsis', tgsis.simplex_table(v_geotype), 'geoid', p_geoid);
    END IF;
    PERFORM tgsis.delete_object_rows('tgsis', 'geometry', 'geoid', p_geoid);
    RETURN true;
END
$$;

COMMENT ON FUNCTION tgsis.delete_geometry(bigint) IS
    'delete a geometry, its vertices, simplices, feature row and cell properties in the session''s version; false if it did not exist';
