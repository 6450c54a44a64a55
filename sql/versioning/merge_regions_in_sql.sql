-- tgsis.merge_regions_in_sql(version, action, remove): merge by region, in SQL, the unsolved conflicting meshes of a version; returns the rows written.
-- The first step of a psql user's tgsis.merge_version / tgsis.refresh_version
-- (docs/merge.md, "The merge by region from psql"), as the Python merge's
-- first step (tgsis.db.merging._merge_by_region): the rights and locks of the
-- merge (tgsis.lock_for_region_merge: parent, then version, waiting for their
-- writers; READ COMMITTED required), the conflicts of now with the regions of
-- the unsolved meshes found and stored (tgsis.find_conflicts), then each
-- unsolved model-1 feature whose regions are stored and whose conflicting
-- regions all have a solution is merged (tgsis.merge_mesh_by_region: written
-- into the version, recorded 'manual'), by key ascending. A feature with a
-- region unsolved is left to the merge's refusal (TG302, as before); one SQL
-- does not merge (average or manual solutions, atoms, parts, models 2 and 3
-- for which the Python client stores regions per slice) is refused by name.
-- Nothing when the Python client merges by region itself in this transaction
-- (tgsis.region_detection = 'client': it set it). Afterwards
-- tgsis.region_detection is 'client' for the transaction, as the Python path
-- leaves it: the merge's own find_conflicts does not find regions again; the
-- caller puts the setting back.
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
BEGIN
    IF current_setting('tgsis.region_detection', true) IS NOT DISTINCT FROM 'client' THEN
        RETURN 0;
    END IF;
    PERFORM tgsis.lock_for_region_merge(p_version, p_action, p_remove);
    v_id := tgsis.version_id(p_version);
    PERFORM FROM tgsis.find_conflicts(p_version);
    PERFORM set_config('tgsis.region_detection', 'client', true);
    FOR v_key IN
        SELECT k.objectkey FROM tgsis.conflicts k
         WHERE k.versionid = v_id AND k.objectclass = 'feature' AND k.solution = 'unsolved'
           AND EXISTS (SELECT FROM tgsis.conflict_regions r
                        WHERE r.versionid = k.versionid AND r.objectclass = k.objectclass AND r.objectkey = k.objectkey)
           AND NOT EXISTS (SELECT FROM tgsis.conflict_regions r
                            WHERE r.versionid = k.versionid AND r.objectclass = k.objectclass AND r.objectkey = k.objectkey
                              AND (r.solution = 'unsolved' OR r.times IS NOT NULL))
         ORDER BY k.objectkey::bigint
    LOOP
        v_written := v_written + tgsis.merge_mesh_by_region(p_version, p_action, v_key::bigint);
    END LOOP;
    RETURN v_written;
END
$$;

COMMENT ON FUNCTION tgsis.merge_regions_in_sql(text, text, boolean) IS
    'the merge by region of a psql merge or refresh: lock the versions, find the conflicts and regions of now, and merge (tgsis.merge_mesh_by_region) each unsolved model-1 feature whose conflicting regions all have a parent/child/base solution into the version; nothing when the Python client merges by region itself; returns the rows written';
