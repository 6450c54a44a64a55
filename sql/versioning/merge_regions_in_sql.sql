-- tgsis.merge_regions_in_sql(version, action, remove): merge by region, in SQL, the unsolved conflicting meshes of a version; returns the rows written.
-- The first step of a psql user's tgsis.merge_version / tgsis.refresh_version
-- (docs/merge.md, "The merge by region from psql"), as the Python merge's
-- first step (tgsis.db.merging._merge_by_region): the rights and locks of the
-- merge (tgsis.lock_for_region_merge: parent, then version, waiting for their
-- writers; READ COMMITTED required), the conflicts of now
-- (tgsis.find_conflicts, its region detection left to this step), then, by key
-- ascending, each unsolved feature that merges by region
-- (tgsis.region_merge_refusal: a static mesh, ...) and has no region stored
-- unsolved is merged (tgsis.merge_mesh_by_region: its regions found, written
-- into the version, recorded 'manual'). One with a conflicting region without
-- a solution is left to the merge's refusal (TG302, as before), its regions
-- stored (tgsis.store_mesh_regions) for the refusal's hint; one SQL does not
-- merge (average or manual solutions recorded with their .npz only) is
-- refused by name.
-- Nothing when the Python client merges by region itself in this transaction
-- (tgsis.region_detection = 'client': it set it). Afterwards
-- tgsis.region_detection is 'client' for the transaction, as the Python path
-- leaves it; the caller puts it back.
CREATE FUNCTION tgsis.merge_regions_in_sql(p_version text, p_action text, p_remove boolean DEFAULT false)
RETURNS bigint
LANGUAGE plpgsql
VOLATILE
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_id      integer;
    v_key     text;
    v_written bigint := 0;
    v_count   bigint;
    v_function text;
BEGIN
    IF current_setting('tgsis.region_detection', true) IS NOT DISTINCT FROM 'client' THEN
        RETURN 0;
    END IF;
    PERFORM tgsis.lock_for_region_merge(p_version, p_action, p_remove);
    v_id := tgsis.version_id(p_version);
    -- the conflicts of now; the regions of each mesh are found once, by its merge below
    PERFORM set_config('tgsis.region_detection', 'client', true);
    PERFORM FROM tgsis.find_conflicts(p_version);
    -- the features of a model merged slice by slice in SQL (its registry row's merge_function: surfaces at
    -- instants instant by instant, tgsis.merge_instants_by_slice; evolving surfaces period by period,
    -- tgsis.merge_periods_by_slice, in sql/temporal/ beside the continuity check it needs); NULL: an
    -- object-level conflict or an unsolved region of an instant, refused below
    FOR v_key, v_function IN
        SELECT k.objectkey, m.merge_function FROM tgsis.conflicts k
          JOIN tgsis.catalog c ON c.classname = tgsis.class_of_geoid(k.objectkey::bigint)
          JOIN tgsis.data_models m ON m.timemodel = c.timemodel
         WHERE k.versionid = v_id AND k.objectclass = 'feature' AND k.solution = 'unsolved'
           AND m.merge_function IS NOT NULL
         ORDER BY k.objectkey::bigint
    LOOP
        EXECUTE format('SELECT tgsis.%I($1, $2, $3)', v_function) INTO v_count USING p_version, p_action, v_key::bigint;
        IF v_count IS NULL THEN
            -- unsolved (a region of an instant without a solution, or an object-level conflict): the regions
            -- of its instants stored, for the merge's refusal to name them (none for other models)
            PERFORM tgsis.store_mesh_regions(p_version, v_key);
        ELSE
            v_written := v_written + v_count;
        END IF;
    END LOOP;
    FOR v_key IN
        SELECT k.objectkey FROM tgsis.conflicts k
         WHERE k.versionid = v_id AND k.objectclass = 'feature' AND k.solution = 'unsolved'
           AND NOT EXISTS (SELECT FROM tgsis.conflict_regions r
                            WHERE r.versionid = k.versionid AND r.objectclass = k.objectclass AND r.objectkey = k.objectkey
                              AND (r.solution = 'unsolved' OR r.times IS NOT NULL))
         ORDER BY k.objectkey::bigint
    LOOP
        IF tgsis.region_merge_refusal(p_version, v_key::bigint) IS NOT NULL THEN
            CONTINUE;  -- it merges as a whole object only (models 2 and 3, deleted on one side, ...): refused below
        END IF;
        BEGIN
            v_count := tgsis.merge_mesh_by_region(p_version, p_action, v_key::bigint);
        EXCEPTION WHEN SQLSTATE 'TG100' THEN  -- new ids beyond bigint (the Python merge refuses it too): refused below
            CONTINUE;
        END;
        IF v_count IS NULL THEN
            -- a region conflict without a solution: its regions stored, for the merge's refusal to name them
            PERFORM tgsis.store_mesh_regions(p_version, v_key);
        ELSE
            v_written := v_written + v_count;
        END IF;
    END LOOP;
    RETURN v_written;
END
$$;

COMMENT ON FUNCTION tgsis.merge_regions_in_sql(text, text, boolean) IS
    'the merge by region of a psql merge or refresh: lock the versions, find the conflicts and regions of now, and merge (tgsis.merge_mesh_by_region) each unsolved model-1 feature whose conflicting regions all have a parent/child/base solution into the version; nothing when the Python client merges by region itself; returns the rows written';

-- internal to the merges: reached only through the SECURITY DEFINER merge, refresh, find_conflicts and
-- resolve functions, as their owner; not executable by PUBLIC (tests/test_function_grants.py)
REVOKE ALL ON FUNCTION tgsis.merge_regions_in_sql(text, text, boolean) FROM PUBLIC;
