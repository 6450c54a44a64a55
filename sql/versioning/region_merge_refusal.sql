-- tgsis.region_merge_refusal(version, geoid): why a feature changed on both sides does not merge by region, or NULL.
-- The refusals of the Python reader (tgsis.db._merge_states.read_merge_states)
-- in SQL, so that SQL region detection (tgsis.mesh_merge_regions, run by
-- tgsis.find_conflicts) merges by region exactly the objects the Python
-- client does: a feature of no class, of a class of another data model than
-- model 1 or of geometry collections, a feature deleted on one side, or one
-- whose attributes (its feature-table row) both sides changed to other
-- values (compared as text: floats exactly, extra_float_digits pinned). The
-- object's rows are read from the storage at the three revision sets (base:
-- the version at its initrevision; parent and version: their working sets),
-- the feature table through tgsis.storage_run (the caller's rights, or the
-- table owner's runner as tgsis's owner).
CREATE FUNCTION tgsis.region_merge_refusal(p_version text, p_geoid bigint)
RETURNS text
LANGUAGE plpgsql
VOLATILE
SET search_path = pg_catalog, pg_temp
SET extra_float_digits = 1
AS $$
DECLARE
    v_version tgsis.versions;
    v_class   tgsis.catalog;
    v_name    text;
BEGIN
    SELECT * INTO v_version FROM tgsis.versions WHERE versionid = tgsis.version_id(p_version);
    IF v_version.parentid IS NULL THEN
        RETURN 'version DEFAULT has no parent to merge with';
    END IF;
    v_name := tgsis.class_of_geoid(p_geoid);
    SELECT * INTO v_class FROM tgsis.catalog WHERE classname = v_name;
    IF NOT FOUND THEN
        RETURN format('feature %s belongs to no feature class', p_geoid);
    END IF;
    IF v_class.timemodel <> 'STATIC' OR tgsis.simplex_table(v_class.geotype) IS NULL THEN
        RETURN format('feature %s of class %s is %s: only a static (model 1) point set, line set, surface or tetrahedral solid merges by region',
                      p_geoid, v_class.classname,
                      CASE WHEN v_class.timemodel <> 'STATIC' THEN 'of model ' || v_class.timemodel ELSE 'a geometry collection' END);
    END IF;
    RETURN tgsis.object_merge_refusal(p_version, p_geoid);
END
$$;

COMMENT ON FUNCTION tgsis.region_merge_refusal(text, bigint) IS
    'why a feature changed both in a version and in its parent does not merge by region (no class, not model 1, a geometry collection, deleted on one side, attributes changed on both sides), or NULL: the refusals of the Python reader, for SQL region detection';

-- internal to the merges, not executable by PUBLIC (tests/test_function_grants.py); tgsis.mesh_merge_work asks it as the calling tgsis role
REVOKE ALL ON FUNCTION tgsis.region_merge_refusal(text, bigint) FROM PUBLIC;
GRANT EXECUTE ON FUNCTION tgsis.region_merge_refusal(text, bigint) TO tgsis_reader;
