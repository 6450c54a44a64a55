-- tgsis.delete_geometry(geoid): remove a geometry with its vertices, simplices, feature row, cell properties and owned members.
-- A GEOMETRYCOLLECTION takes the members it owns (tgsis.geometry.collection)
-- with it, each with its rows; geometries it only lists in geoids stay.
-- Members cannot be collections, so one level is the whole recursion.
CREATE FUNCTION tgsis.delete_geometry(p_geoid bigint)
RETURNS boolean
LANGUAGE plpgsql
AS $$
DECLARE
    v_geo     tgsis.geometry;
    v_ids     bigint[];
    v_geotype text;
    v_class   record;
BEGIN
    SELECT * INTO v_geo FROM tgsis.geometry WHERE geoid = p_geoid FOR UPDATE;
    IF NOT FOUND THEN
        RETURN false;
    END IF;
    IF v_geo.collection IS NOT NULL THEN
        RAISE EXCEPTION 'geometry % is a member of collection % and is deleted only with it', p_geoid, v_geo.collection
            USING ERRCODE = 'TG202',
                  HINT = format('SELECT tgsis.delete_geometry(%s) deletes the collection with its members', v_geo.collection);
    END IF;
    -- the geometry and the members it owns
    SELECT ARRAY[p_geoid] || coalesce(array_agg(geoid ORDER BY geoid), '{}') INTO v_ids
      FROM tgsis.geometry WHERE collection = p_geoid;
    -- cell properties have no foreign key (bulk upload speed): remove them by class;
    -- those of a collection's members are in its class's table, keyed by member geoid
    FOR v_class IN SELECT schemaname, cellprotable FROM tgsis.catalog WHERE geotype = v_geo.geotype LOOP
        EXECUTE format('DELETE FROM %I.%I WHERE _geoid = ANY ($1)', v_class.schemaname, v_class.cellprotable) USING v_ids;
    END LOOP;
    DELETE FROM tgsis.vrtx WHERE geoid = ANY (v_ids);
    FOR v_geotype IN SELECT DISTINCT geotype FROM tgsis.geometry
                      WHERE geoid = ANY (v_ids) AND geotype <> 'GEOMETRYCOLLECTION' LOOP
        EXECUTE format('DELETE FROM tgsis.%I WHERE geoid = ANY ($1)', tgsis.simplex_table(v_geotype)) USING v_ids;
    END LOOP;
    DELETE FROM tgsis.geometry WHERE geoid = ANY (v_ids);  -- the feature row goes with it (ON DELETE CASCADE)
    RETURN true;
END
$$;

COMMENT ON FUNCTION tgsis.delete_geometry(bigint) IS
    'delete a geometry, its vertices, simplices, feature row and cell properties, and the members a collection owns (not those it only lists); refuses (TG202) an owned member; false if it did not exist';
