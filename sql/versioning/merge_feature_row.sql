-- tgsis.merge_feature_row(geoid, columns, parent set, revision, working set): bring the parent's values of a feature's properties into the version's row; rows changed.
-- A step of the SQL merge by region's write (tgsis.merge_mesh_by_region), as
-- tgsis.db._attribute_edits writes them in Python: the columns the parent
-- alone changed (tgsis.merge_attribute_edits) are set in the feature row the
-- version's working set shows, to the values of the row the parent's set
-- shows, copied from that row (exact: no value goes through text). Written
-- as the class's view's INSTEAD OF trigger writes an UPDATE
-- (tgsis.versioning_trigger_source): a row of the working revision is
-- changed in place, any other is closed in it (lastrevs) and written anew
-- with that revision; the object is noted changed in that revision
-- (tgsis.revision_objects). The feature table's storage is its class owner's:
-- every statement on it goes through tgsis.storage_run (as that owner, never
-- as tgsis's). The caller checks the rights (the role's UPDATE of the columns)
-- and has the session in the version's working revision. Returns 1 when the
-- version shows a row of the feature (the view UPDATE's row count), else 0.
CREATE FUNCTION tgsis.merge_feature_row(p_geoid bigint, p_columns text[], p_parentset integer[], p_revision integer,
                                        p_workingset integer[])
RETURNS bigint
LANGUAGE plpgsql
VOLATILE
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_class tgsis.catalog;
    v_t     tgsis.versioned_tables;
    v_ver   text;
    v_cols  text;
    v_vals  text;
    v_sets  text;
    v_count bigint;
    -- the parent's row, one or none, joined to the statement's single row
    v_their CONSTANT text := 'LEFT JOIN %1$s p ON p.%2$I = $5[1] AND p.revision = ANY ($3) AND NOT (p.lastrevs && $3)';
BEGIN
    IF cardinality(p_columns) = 0 THEN
        RETURN 0;
    END IF;
    SELECT c.* INTO v_class FROM tgsis.catalog c WHERE c.classname = tgsis.class_of_geoid(p_geoid);
    SELECT t.* INTO v_t FROM tgsis.versioned_tables t
     WHERE t.schemaname = v_class.schemaname AND t.tablename = v_class.featuretable;
    v_ver := format('%I.%I', v_t.schemaname, v_t.tablename || '_ver');
    -- every stored column but the generated ones (as tgsis.copy_object_state copies a row)
    SELECT string_agg(format('%I', a.attname), ', ' ORDER BY a.attnum),
           string_agg(CASE WHEN a.attname = ANY (p_columns) THEN format('p.%I', a.attname) ELSE format('v.%I', a.attname) END,
                      ', ' ORDER BY a.attnum)
      INTO v_cols, v_vals
      FROM pg_catalog.pg_attribute a
     WHERE a.attrelid = v_ver::regclass AND a.attnum > 0 AND NOT a.attisdropped AND a.attgenerated = ''
       AND a.attname NOT IN ('revision', 'lastrevs');
    SELECT string_agg(format('%I = p.%I', u.c, u.c), ', ' ORDER BY u.o) INTO v_sets
      FROM unnest(p_columns) WITH ORDINALITY AS u(c, o);
    -- the version's row of its working revision: changed in place
    SELECT r[1]::bigint INTO v_count FROM tgsis.storage_run(v_t, true, format(
        'UPDATE %1$s v SET %3$s FROM (SELECT) AS one ' || v_their || '
          WHERE v.%2$I = $5[1] AND v.revision = $4 AND NOT (v.lastrevs && $2)',
        v_ver, v_t.objectkeyfield, v_sets),
        p_2 => p_workingset, p_3 => p_parentset, p_4 => p_revision, p_5 => ARRAY[p_geoid]) AS r;
    IF v_count = 0 THEN
        -- a row of an older revision: closed in the working one, written anew there
        SELECT r[1]::bigint INTO v_count FROM tgsis.storage_run(v_t, true, format(
            'WITH v AS (UPDATE %1$s v SET lastrevs = v.lastrevs || $4
                         WHERE v.%2$I = $5[1] AND v.revision = ANY ($2) AND NOT (v.lastrevs && $2) AND v.revision <> $4
                        RETURNING v.*)
             INSERT INTO %1$s (%3$s, revision) SELECT %4$s, $4 FROM v ' || v_their,
            v_ver, v_t.objectkeyfield, v_cols, v_vals),
            p_2 => p_workingset, p_3 => p_parentset, p_4 => p_revision, p_5 => ARRAY[p_geoid]) AS r;
    END IF;
    IF v_count > 0 THEN
        PERFORM tgsis.note_changed_objects(v_t.schemaname, v_t.tablename, p_revision, ARRAY[p_geoid::text]);
    END IF;
    RETURN least(v_count, 1);
END
$$;

COMMENT ON FUNCTION tgsis.merge_feature_row(bigint, text[], integer[], integer, integer[]) IS
    'bring the parent''s values of some properties of a feature into the row its version''s working set shows, copied from the parent''s row through tgsis.storage_run (in place in the working revision, else closed and written anew), noted in tgsis.revision_objects; for the SQL merge by region; returns 1 when the version shows a row, else 0';

-- internal to the psql merge by region (reached only through the SECURITY DEFINER merge, find_conflicts and
-- resolve functions): not executable by PUBLIC, like tgsis's other internal helpers
REVOKE ALL ON FUNCTION tgsis.merge_feature_row(bigint, text[], integer[], integer, integer[]) FROM PUBLIC;
