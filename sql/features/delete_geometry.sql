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
    v_own   text;   -- the feature's class (tgsis.class_of_geoid)
BEGIN
    PERFORM tgsis.require_storage();  -- a bare CREATE EXTENSION: say what to run (geometry/require_storage.sql)
    PERFORM tgsis.plain_write_check('tgsis', 'geometry');  -- not "in" a version while features are plain
    PERFORM tgsis.feature_write_lock(p_geoid);  -- a check-in deciding from this object's state finishes first
    -- a feature of a class the role may neither UPDATE nor DELETE: refused by name (42501), not "not there"
    -- (row-level security keeps its rows from the locking read below, so it would answer false)
    PERFORM tgsis.check_class_write(ARRAY[p_geoid], 'UPDATE, DELETE');
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
    IF EXISTS (SELECT FROM tgsis.unversioned_features u WHERE u.geoid = p_geoid) THEN
        PERFORM tgsis.unversioned_revision(ARRAY[p_geoid]);  -- of a class without versioning: in DEFAULT only (TG305)
    END IF;
    -- the feature row: its foreign key is gone once model 1 is versioned, so
    -- delete it explicitly; cell properties of a collection's members are in
    -- its class's table, keyed by member geoid. Only the tables of the
    -- feature's own class (tgsis.class_of_geoid): those of the other classes
    -- hold nothing of it, and per-class rights may keep the caller from them.
    v_own := tgsis.class_of_geoid(p_geoid);  -- once: it reads every class's feature table
    FOR v_class IN SELECT t.schemaname, t.tablename, t.kind FROM tgsis.class_tables t JOIN tgsis.catalog c USING (classname)
                    WHERE c.geotype = v_geo.geotype AND c.timemodel = v_geo.timemodel
                      AND c.classname = v_own ORDER BY t.classname, t.position DESC LOOP
        PERFORM tgsis.delete_object_rows(v_class.schemaname, v_class.tablename, '_geoid',
                                         CASE v_class.kind WHEN 'feature' THEN ARRAY[p_geoid] ELSE v_ids END);
    END LOOP;
    -- the storage of their models, tgsis.geometry last (tgsis.model_tables_of)
    FOR v_table IN SELECT * FROM tgsis.model_tables_of(v_ids) LOOP
        PERFORM tgsis.delete_object_rows('tgsis', v_table, 'geoid', v_ids);
    END LOOP;
    PERFORM tgsis.forget_unversioned(v_ids);  -- a feature of no version leaves no record behind
    RETURN true;
END
$$;

COMMENT ON FUNCTION tgsis.delete_geometry(bigint) IS
    'delete a geometry with its rows in its data model''s tables (tgsis.model_tables: vertices, simplices, atoms, parts; instants and periods of temporal ones), its feature row, cell and per-instant properties (tgsis.class_tables), and the members a collection owns (not those it only lists), in the session''s version; refuses (TG202) an owned member; false if it did not exist';
