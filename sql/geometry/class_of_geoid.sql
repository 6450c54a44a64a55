-- tgsis.class_of_geoid(geoid): the feature class a geometry belongs to (its own, or its owning collection's), for messages.
-- tgsis.check_class_write names the class a role may not change. SECURITY
-- DEFINER: the class's tables may be ones the role cannot read; it returns
-- the class's name only (tgsis.catalog, readable by readers, lists them).
CREATE FUNCTION tgsis.class_of_geoid(p_geoid bigint)
RETURNS text
LANGUAGE plpgsql
STABLE
SECURITY DEFINER
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_class    record;
    v_found    boolean;
    v_geometry regclass := tgsis.class_storage('tgsis.geometry');
    v_ids      bigint[];
BEGIN
    EXECUTE format('SELECT array_agg(DISTINCT g.collection) FROM %s g WHERE g.geoid = $1 AND g.collection IS NOT NULL', v_geometry)
       INTO v_ids USING p_geoid;
    v_ids := array_prepend(p_geoid, coalesce(v_ids, '{}'));
    FOR v_class IN
        SELECT c.classname, tgsis.class_storage(to_regclass(format('%I.%I', c.schemaname, c.featuretable))) AS rel
          FROM tgsis.catalog c ORDER BY c.classname
    LOOP
        CONTINUE WHEN v_class.rel IS NULL;
        EXECUTE format('SELECT EXISTS (SELECT FROM %s f WHERE f._geoid = ANY ($1))', v_class.rel) INTO v_found USING v_ids;
        IF v_found THEN
            RETURN v_class.classname;
        END IF;
    END LOOP;
    RETURN NULL;
END
$$;

COMMENT ON FUNCTION tgsis.class_of_geoid(bigint) IS
    'the feature class whose feature table holds the geoid (in any revision) or the collection owning it; NULL: a geometry of no class';
