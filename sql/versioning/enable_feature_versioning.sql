-- tgsis.enable_feature_versioning(): version model 1 and every feature class as one object class, 'feature', keyed by geoid.
-- iudorder: geometry 0, vertices, instants and periods 1, simplices, atoms, parts,
-- geometry instants and nodes 2, feature tables 3, cell and per-instant properties 4.
-- Classes registered later are versioned as they are created.
CREATE FUNCTION tgsis.enable_feature_versioning()
RETURNS integer
LANGUAGE plpgsql
VOLATILE
SECURITY DEFINER
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_table text;
    v_class text;
    v_count integer;
BEGIN
    SELECT count(*) INTO v_count FROM tgsis.versioned_tables WHERE objectclass = 'feature';
    FOR v_class IN SELECT classname FROM tgsis.catalog ORDER BY classname LOOP
        PERFORM tgsis.version_class_tables(v_class);
    END LOOP;
    FOREACH v_table IN ARRAY ARRAY['geometry', 'vrtx', 'point', 'segment', 'trgl', 'tetra', 'atom', 'part', 'times', 'times_vrtx', 'times_trgl',
                                   'timem', 'timet', 'node', 'd4dtrgl', 'd4dvrtx'] LOOP
        IF NOT EXISTS (SELECT FROM tgsis.versioned_tables WHERE schemaname = 'tgsis' AND tablename = v_table) THEN
            PERFORM tgsis.enable_versioning_rel(format('tgsis.%I', v_table)::regclass, 'geoid', 'feature',
                                                CASE WHEN v_table = 'geometry' THEN 0
                                                     WHEN v_table IN ('vrtx', 'times', 'timem') THEN 1 ELSE 2 END);
        END IF;
    END LOOP;
    FOR v_class IN SELECT classname FROM tgsis.catalog ORDER BY classname LOOP
        PERFORM tgsis.create_class_view(v_class);
    END LOOP;
    RETURN (SELECT count(*) FROM tgsis.versioned_tables WHERE objectclass = 'feature') - v_count;
END
$$;

REVOKE ALL ON FUNCTION tgsis.enable_feature_versioning() FROM PUBLIC;

COMMENT ON FUNCTION tgsis.enable_feature_versioning() IS
    'version tgsis.geometry, vrtx, point, segment, trgl, tetra, atom, part, the model-2 and model-3 tables (times*, timem, timet, node, d4dtrgl, d4dvrtx) and every feature class''s tables as object class ''feature'' (key geoid/_geoid); returns the number of tables newly versioned';
