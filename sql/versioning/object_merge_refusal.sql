-- tgsis.object_merge_refusal(version, geoid): why a feature changed on both sides does not merge by its parts (deleted on one side, attributes changed on both), or NULL.
-- The refusals the Python readers (tgsis.db._merge_states: read_merge_states,
-- read_sliced_states) share for every data model, in SQL: a feature deleted
-- on one side, or one whose attributes (its feature-table row) both sides
-- changed to other values (compared as text: floats exactly,
-- extra_float_digits pinned). tgsis.region_merge_refusal (model 1) and
-- tgsis.merge_sliced_sets (the psql merges of models 2 and 3) ask it. The object's rows are read
-- from the storage at the three revision sets (base: the version at its
-- initrevision; parent and version: their working sets), the feature table
-- through tgsis.storage_run (the caller's rights, or the table owner's runner
-- as tgsis's owner).
CREATE FUNCTION tgsis.object_merge_refusal(p_version text, p_geoid bigint)
RETURNS text
LANGUAGE plpgsql
VOLATILE
SET search_path = pg_catalog, pg_temp
SET extra_float_digits = 1
AS $$
DECLARE
    v_version tgsis.versions;
    v_parent  tgsis.versions;
    v_base    integer[];
    v_class   tgsis.catalog;
    v_seen    integer;
    v_t       tgsis.versioned_tables;
    v_cols    text;
    v_rows    text[];
BEGIN
    SELECT * INTO v_version FROM tgsis.versions WHERE versionid = tgsis.version_id(p_version);
    IF v_version.parentid IS NULL THEN
        RETURN 'version DEFAULT has no parent to merge with';
    END IF;
    SELECT * INTO v_parent FROM tgsis.versions WHERE versionid = v_version.parentid;
    v_base := tgsis.revision_set(v_version.versionid, v_version.initrevision);
    SELECT * INTO v_class FROM tgsis.catalog WHERE classname = tgsis.class_of_geoid(p_geoid);
    IF NOT FOUND THEN
        RETURN format('feature %s belongs to no feature class', p_geoid);
    END IF;
    -- where the geometry row is seen: 1 base, 2 parent, 4 version
    EXECUTE format('SELECT coalesce(bit_or(((v.revision = ANY ($2) AND NOT (v.revclosed AND v.lastrevs && $2))::integer)'
                   ' | ((v.revision = ANY ($3) AND NOT (v.revclosed AND v.lastrevs && $3))::integer << 1)'
                   ' | ((v.revision = ANY ($4) AND NOT (v.revclosed AND v.lastrevs && $4))::integer << 2)), 0)'
                   ' FROM %s v WHERE v.geoid = $1', tgsis.storage_table('tgsis', 'geometry'))
       INTO v_seen USING p_geoid, v_base, v_parent.workingset, v_version.workingset;
    IF v_seen & 6 <> 6 THEN
        RETURN format('feature %s of class %s was deleted in version %s and changed in %s: a deletion does not merge by region',
                      p_geoid, v_class.classname,
                      quote_literal(CASE WHEN v_seen & 4 = 0 THEN v_version.name ELSE v_parent.name END),
                      quote_literal(CASE WHEN v_seen & 4 = 0 THEN v_parent.name ELSE v_version.name END));
    END IF;
    -- the attributes: the feature-table row of each side, as text (floats exactly)
    SELECT * INTO v_t FROM tgsis.versioned_tables t
     WHERE t.schemaname = v_class.schemaname AND t.tablename = v_class.featuretable;
    IF FOUND THEN
        SELECT string_agg(format('v.%I::text', a.attname), ', ' ORDER BY a.attnum) INTO v_cols
          FROM pg_catalog.pg_attribute a
         WHERE a.attrelid = pg_catalog.to_regclass(format('%I.%I', v_class.schemaname, v_class.featuretable))
           AND a.attnum > 0 AND NOT a.attisdropped;
        -- one text per side (base, parent, version): the row's column texts, or NULL when the side lacks it
        SELECT array_agg(r[2] ORDER BY r[1]) INTO v_rows
          FROM tgsis.storage_run(v_t, false, format(
                 'SELECT ARRAY[s.side::text, (SELECT ARRAY[%1$s]::text FROM %2$I.%3$I v
                                               WHERE v._geoid = $1[1]::bigint
                                                 AND v.revision = ANY (s.revs) AND NOT (v.revclosed AND v.lastrevs && s.revs))]
                    FROM (VALUES (1, $2), (2, $5::integer[]), (3, $3)) AS s (side, revs)',
                 v_cols, v_class.schemaname, v_class.featuretable || '_ver'),
               p_1 => ARRAY[p_geoid::text], p_2 => v_base, p_3 => v_version.workingset,
               p_5 => v_parent.workingset::bigint[]) AS r;
        IF v_rows[2] IS DISTINCT FROM v_rows[3] AND v_rows[2] IS DISTINCT FROM v_rows[1]
           AND v_rows[3] IS DISTINCT FROM v_rows[1] THEN
            RETURN format('feature %s of class %s: its attributes were changed both in version %s and in its parent %s, to other values: the merge by region merges the mesh only',
                          p_geoid, v_class.classname, quote_literal(v_version.name), quote_literal(v_parent.name));
        END IF;
    END IF;
    RETURN NULL;
END
$$;

-- (an internal: the psql merges ask it, and tgsis.mesh_merge_regions, which a tgsis role may call as itself)
REVOKE ALL ON FUNCTION tgsis.object_merge_refusal(text, bigint) FROM PUBLIC;
GRANT EXECUTE ON FUNCTION tgsis.object_merge_refusal(text, bigint) TO tgsis_reader;

COMMENT ON FUNCTION tgsis.object_merge_refusal(text, bigint) IS
    'why a feature changed both in a version and in its parent does not merge by its parts whatever its data model (deleted on one side, attributes changed on both sides), or NULL';
