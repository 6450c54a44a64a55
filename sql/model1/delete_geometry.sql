-- tgsis.delete_geometry(geoid): remove a geometry with its vertices, simplices, feature row, cell properties and owned members.
-- A GEOMETRYCOLLECTION takes the members it owns (tgsis.geometry.collection)
-- with it, each with its rows; geometries it only lists in geoids stay.
-- Members cannot be collections, so one level is the whole recursion.
-- Works in the session's version: on versioned tables the rows are closed
-- set-based (tgsis.delete_object_rows), not one trigger call per vertex.
CREATE FUNCTION tgsis.delete_geometry(p_geoid bigint)
RETURNS boolean
LANGUAGE plpgsql
AS $$
DECLARE
    v_geo   record;
    v_ids   bigint[];
    v_class record;
    v_table text;
BEGIN
    PERFORM tgsis.plain_write_check('tgsis', 'geometry');  -- not "in" a version while features are plain
    PERFORM tgsis.feature_write_lock(p_geoid);  -- a check-in deciding from this object's state finishes first
    SELECT geotype, collection, timemodel INTO v_geo FROM tgsis.geometry WHERE geoid = p_geoid FOR UPDATE;
    IF NOT FOUND THEN
        RETURN false;
    END IF;
    IF v_geo.collection IS NOT NULL THEN
        RAISE EXCEPTION 'geometry % is a member of collection % and is deleted only with it', p_geoid, v_geo.collection
            USING ERRCODE = 'TG202',
                  HINT = format('SELECT tgsis.delete_geometry(%s) deletes the collection with its members', v_geo.collection);
    END IF;
    -- members first, the collection last (its row is what owns them)
    SELECT coalesce(array_agg(geoid ORDER BY geoid), '{}') || p_geoid INTO v_ids
      FROM tgsis.geometry WHERE collection = p_geoid;
    -- the feature row: its foreign key is gone once model 1 is versioned, so
    -- delete it explicitly; cell properties of a collection's members are in
    -- its class's table, keyed by member geoid
    FOR v_class IN SELECT schemaname, featuretable, cellprotable, otherprotable, protablename FROM tgsis.catalog
                    WHERE geotype = v_geo.geotype AND timemodel = v_geo.timemodel LOOP
        PERFORM tgsis.delete_object_rows(v_class.schemaname, v_class.cellprotable, '_geoid', v_ids);
        IF v_class.otherprotable IS NOT NULL THEN
            PERFORM tgsis.delete_object_rows(v_class.schemaname, v_class.otherprotable, '_geoid', v_ids);
        END IF;
        IF v_class.protablename IS NOT NULL THEN
            PERFORM tgsis.delete_object_rows(v_class.schemaname, v_class.protablename, '_geoid', v_ids);
        END IF;
        PERFORM tgsis.delete_object_rows(v_class.schemaname, v_class.featuretable, '_geoid', ARRAY[p_geoid]);
    END LOOP;
    IF v_geo.timemodel = 'INSTANTS' THEN
        FOREACH v_table IN ARRAY ARRAY['times_trgl', 'times_vrtx', 'times'] LOOP
            PERFORM tgsis.delete_object_rows('tgsis', v_table, 'geoid', v_ids);
        END LOOP;
    ELSIF v_geo.timemodel = 'EVOLVING' THEN
        FOREACH v_table IN ARRAY ARRAY['d4dvrtx', 'd4dtrgl', 'node', 'timet', 'timem'] LOOP
            PERFORM tgsis.delete_object_rows('tgsis', v_table, 'geoid', v_ids);
        END LOOP;
    END IF;
    PERFORM tgsis.delete_object_rows('tgsis', 'atom', 'geoid', v_ids);
    PERFORM tgsis.delete_object_rows('tgsis', 'part', 'geoid', v_ids);
    PERFORM tgsis.delete_object_rows('tgsis', 'vrtx', 'geoid', v_ids);
    FOR v_geo IN SELECT DISTINCT geotype FROM tgsis.geometry WHERE geoid = ANY (v_ids) AND geotype <> 'GEOMETRYCOLLECTION' LOOP
        PERFORM tgsis.delete_object_rows('tgsis', tgsis.simplex_table(v_geo.geotype), 'geoid', v_ids);
    END LOOP;
    PERFORM tgsis.delete_object_rows('tgsis', 'geometry', 'geoid', v_ids);
    RETURN true;
END
$$;

COMMENT ON FUNCTION tgsis.delete_geometry(bigint) IS
    'delete a geometry, its vertices, simplices, atoms, parts (instants and periods of temporal ones), feature row, cell and per-instant properties, and the members a collection owns (not those it only lists), in the session''s version; refuses (TG202) an owned member; false if it did not exist';
