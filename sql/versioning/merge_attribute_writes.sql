-- tgsis.merge_attribute_writes(version, geoid, base, parent set, version set): the parent's attribute edits a psql merge brings, as the arguments of tgsis.merge_apply_attribute_edits.
-- tgsis.merge_attribute_edits (the attributes the parent alone changed, and
-- those both changed) grouped per view, as the psql merges that write a
-- feature's merged state first use them: p_views, p_keys, p_sets the
-- geometry row's view, key column and SET list (built with %I / %L),
-- p_fcols the feature-row columns to copy from the parent's row (NULL:
-- none), p_both the columns both sides changed to other values (NULL: none).
-- Shared by tgsis.merge_mesh_by_region (which refuses p_both),
-- tgsis.merge_instants_by_slice and tgsis.merge_periods_by_slice.
CREATE FUNCTION tgsis.merge_attribute_writes(p_version text, p_geoid bigint, p_base integer[], p_parentset integer[],
                                             p_versionset integer[], OUT p_views text[], OUT p_keys text[],
                                             OUT p_sets text[], OUT p_fcols text[], OUT p_both text)
LANGUAGE plpgsql
VOLATILE
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_attr record;
BEGIN
    p_views := '{}';
    p_keys := '{}';
    p_sets := '{}';
    FOR v_attr IN
        SELECT e.viewname, e.keycolumn,
               string_agg(e.columnname, ', ' ORDER BY e.o) FILTER (WHERE e.both_sides) AS both_columns,
               string_agg(format('%I = %L', e.columnname, e.value), ', ' ORDER BY e.o) AS sets,
               array_agg(e.columnname ORDER BY e.o) AS columns
          FROM (SELECT a.*, row_number() OVER () AS o
                  FROM tgsis.merge_attribute_edits(p_version, p_geoid, p_base, p_parentset, p_versionset) AS a) AS e
         GROUP BY e.viewname, e.keycolumn ORDER BY min(e.o)
    LOOP
        IF v_attr.both_columns IS NOT NULL THEN
            p_both := concat_ws(', ', p_both, v_attr.both_columns);
        END IF;
        IF v_attr.viewname = 'tgsis.geometry' THEN
            p_views := p_views || v_attr.viewname;
            p_keys := p_keys || v_attr.keycolumn;
            p_sets := p_sets || v_attr.sets;
        ELSE
            p_fcols := v_attr.columns;  -- the feature row's: copied from the parent's row
        END IF;
    END LOOP;
END
$$;

-- internal to the psql merges, not executable by PUBLIC (tests/test_function_grants.py)
REVOKE ALL ON FUNCTION tgsis.merge_attribute_writes(text, bigint, integer[], integer[], integer[]) FROM PUBLIC;

COMMENT ON FUNCTION tgsis.merge_attribute_writes(text, bigint, integer[], integer[], integer[]) IS
    'the parent''s attribute edits a psql merge brings into the version, grouped as tgsis.merge_apply_attribute_edits takes them (geometry-row views, keys and SET lists; feature-row columns), and the columns both sides changed';
