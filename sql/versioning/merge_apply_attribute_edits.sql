-- tgsis.merge_apply_attribute_edits(geoid, views, keys, sets, feature columns, parent set, revision, working set): bring the parent's attribute edits into the version; rows changed.
-- The last write of the psql merges that write a feature's merged state
-- into the version first (tgsis.merge_mesh_by_region,
-- tgsis.merge_instants_by_slice), as tgsis.db._attribute_edits writes them
-- in Python: per view (tgsis.geometry's columns, from
-- tgsis.merge_attribute_edits, whose SET lists are built with %I / %L), one
-- UPDATE of its columns; the feature row's columns copied from the parent's
-- row (tgsis.merge_feature_row). The caller has checked the rights
-- (tgsis.merge_write_rights) and has the session in the version's working
-- revision. Not executable by PUBLIC: its arguments are statement text.
CREATE FUNCTION tgsis.merge_apply_attribute_edits(p_geoid bigint, p_views text[], p_keys text[], p_sets text[],
                                                  p_fcols text[], p_parentset integer[], p_revision integer,
                                                  p_workingset integer[])
RETURNS bigint
LANGUAGE plpgsql
VOLATILE
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_i       integer;
    v_count   bigint;
    v_written bigint := 0;
BEGIN
    FOR v_i IN 1 .. coalesce(cardinality(p_views), 0) LOOP  -- a view's columns in one UPDATE
        EXECUTE format('UPDATE %s SET %s WHERE %I = $1', p_views[v_i], p_sets[v_i], p_keys[v_i]) USING p_geoid;
        GET DIAGNOSTICS v_count = ROW_COUNT;
        v_written := v_written + v_count;
    END LOOP;
    IF p_fcols IS NOT NULL THEN
        v_written := v_written + tgsis.merge_feature_row(p_geoid, p_fcols, p_parentset, p_revision, p_workingset);
    END IF;
    RETURN v_written;
END
$$;

COMMENT ON FUNCTION tgsis.merge_apply_attribute_edits(bigint, text[], text[], text[], text[], integer[], integer, integer[]) IS
    'the parent''s attribute edits brought into the version by a psql merge that writes the merged state first: one UPDATE per view of the columns tgsis.merge_attribute_edits lists, the feature row''s columns copied from the parent''s row (tgsis.merge_feature_row); returns the rows changed';

REVOKE ALL ON FUNCTION tgsis.merge_apply_attribute_edits(bigint, text[], text[], text[], text[], integer[], integer, integer[]) FROM PUBLIC;
