-- tgsis.chunk_class_by_default(class): store a STATIC class's property tables in chunks when the default says so (issue 40, the flip).
-- docs/storage.md, "Property chunks by default: the rule". The default holds
-- when model 1 is stored in chunks in this database (tgsis.vrtx behind its
-- face: tgsis.stored_in_chunks, read from the system catalogs, not from
-- anything a caller wrote) and tgsis.chosen_storage() is 'chunks' (the
-- setting tgsis.storage unset, empty or chunks; rows keeps rows; another value
-- TG001). Then every property table of the class that is still rows and has a
-- property column is switched by tgsis.store_class_in_chunks, as tgsis's owner:
-- register_feature_class calls it for a new class (its tables empty: no
-- conversion) and add_property for a table that gets its first property column
-- (a class registered without one). A temporal class stays rows (property
-- chunks serve STATIC classes only), so does a class with no property column
-- (nothing a chunk would hold). Internal: only register_feature_class and
-- add_property, SECURITY DEFINER both, call it, after their own checks of the
-- caller (a tgsis_admin); the switch then runs as the owner of the tables, who
-- owns the chunk tables as it owns rows tables, and the face takes the table's
-- grants. Returns whether a table was switched.
CREATE FUNCTION tgsis.chunk_class_by_default(p_class text)
RETURNS boolean
LANGUAGE plpgsql
VOLATILE
SECURITY DEFINER
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_class tgsis.catalog;
BEGIN
    SELECT * INTO v_class FROM tgsis.catalog c WHERE c.classname = p_class;
    IF NOT FOUND OR v_class.timemodel <> 'STATIC' OR NOT tgsis.stored_in_chunks('vrtx')
       OR tgsis.chosen_storage() <> 'chunks' THEN
        RETURN false;
    END IF;
    -- a property table still rows with a property column: what store_class_in_chunks would switch
    IF NOT EXISTS (SELECT FROM unnest(ARRAY[v_class.cellprotable, v_class.otherprotable]) AS u(t)
                    WHERE t IS NOT NULL
                      AND to_regclass(tgsis.chunk_relation(format('%I.%I', v_class.schemaname, t), '_chunk')) IS NULL
                      AND EXISTS (SELECT FROM pg_attribute a
                                   WHERE a.attrelid = tgsis.storage_table(v_class.schemaname, t)::regclass
                                     AND a.attnum > 0 AND NOT a.attisdropped
                                     AND a.attname NOT IN ('_geoid', '_idx', 'revision', 'lastrevs', 'revclosed'))) THEN
        RETURN false;
    END IF;
    PERFORM tgsis.store_class_in_chunks(p_class);
    RETURN true;
END
$$;

REVOKE ALL ON FUNCTION tgsis.chunk_class_by_default(text) FROM PUBLIC;

COMMENT ON FUNCTION tgsis.chunk_class_by_default(text) IS
    'internal (register_feature_class, add_property): store the property tables of a STATIC class in chunks (tgsis.store_class_in_chunks, as tgsis''s owner) when model 1 is stored in chunks in this database and tgsis.chosen_storage() is chunks; each table still rows with a property column is switched, a temporal class or one with no property column stays rows; returns whether it switched';
