-- tgsis.merge_attribute_edits(version, geoid, base, parent set, version set): the feature's attributes the parent alone changed, and those both changed.
-- What the SQL merge by region brings into the version with the merged mesh
-- (tgsis.merge_mesh_by_region), as tgsis.db._attribute_edits does in Python:
-- column by column, the attributes of the geometry row (name, collection,
-- alive, colour, z convention, CRS, metadata) and every column of the feature
-- row, as exact text (extra_float_digits pinned; dates and instants in ISO
-- form, DateStyle pinned, as the Python reader reads them), in the base (the version's
-- initial revision set), the parent and the version. A value the parent
-- changed and the version did not is one to bring (both_sides false); one both
-- changed to other values is both_sides true (the merge by region is then refused).
-- A missing row reads as NULLs. Read from the storage by the sets: the same
-- rows the versioned views show for them.
CREATE FUNCTION tgsis.merge_attribute_edits(p_version text, p_geoid bigint, p_base integer[], p_parentset integer[],
                                            p_versionset integer[])
RETURNS TABLE (viewname text, keycolumn text, columnname text, value text, both_sides boolean)
LANGUAGE plpgsql
STABLE
SET search_path = pg_catalog, pg_temp
SET extra_float_digits = 1
SET DateStyle = 'ISO, YMD'
AS $$
#variable_conflict use_column
DECLARE
    v_class tgsis.catalog;
    v_view  record;
    v_cols  text[];
    v_t     tgsis.versioned_tables;
    v_rows  text[];
    v_base  text[];
    v_their text[];
    v_ours  text[];
BEGIN
    SELECT c.* INTO v_class FROM tgsis.catalog c WHERE c.classname = tgsis.class_of_geoid(p_geoid);
    FOR v_view IN
        SELECT 'tgsis'::text AS schemaname, 'geometry'::text AS tablename, 'geoid'::text AS keycol,
               ARRAY['geoname', 'collection', 'alive', 'colorred', 'colorgreen', 'colorblue', 'zpositive', 'crs',
                     'metadata'] AS cols
        UNION ALL
        SELECT v_class.schemaname, v_class.featuretable, '_geoid',
               ARRAY(SELECT a.attname::text FROM pg_catalog.pg_attribute a
                      WHERE a.attrelid = pg_catalog.to_regclass(format('%I.%I', v_class.schemaname, v_class.featuretable))
                        AND a.attnum > 0 AND NOT a.attisdropped AND a.attname <> '_geoid' ORDER BY a.attnum)
    LOOP
        IF cardinality(v_view.cols) = 0 THEN
            CONTINUE;
        END IF;
        -- each side's row as one text[] (NULL: no row), through tgsis.storage_run: the feature table's storage
        -- is its owner's, read as that owner, never as tgsis's
        SELECT * INTO v_t FROM tgsis.versioned_tables t
         WHERE t.schemaname = v_view.schemaname AND t.tablename = v_view.tablename;
        v_rows := ARRAY(
            SELECT r[2] FROM tgsis.storage_run(v_t, false, format(
                'SELECT ARRAY[s.side::text, (SELECT ARRAY[%1$s]::text FROM %2$I.%3$I v
                                              WHERE v.%4$I = $1[1]::bigint
                                                AND v.revision = ANY (s.revs) AND NOT (v.lastrevs && s.revs))]
                   FROM (VALUES (1, $2), (2, $3), (3, $5::integer[])) AS s (side, revs)',
                (SELECT string_agg(format('v.%I::text', c), ', ' ORDER BY o) FROM unnest(v_view.cols) WITH ORDINALITY AS u(c, o)),
                v_view.schemaname, v_view.tablename || '_ver', v_view.keycol),
                p_1 => ARRAY[p_geoid::text], p_2 => p_base, p_3 => p_parentset, p_5 => p_versionset::bigint[]) AS r
             ORDER BY r[1]::integer);
        v_base := v_rows[1]::text[];
        v_their := v_rows[2]::text[];
        v_ours := v_rows[3]::text[];
        RETURN QUERY
        SELECT format('%I.%I', v_view.schemaname, v_view.tablename), v_view.keycol, u.c, v_their[u.o],
               v_ours[u.o] IS DISTINCT FROM v_base[u.o]
          FROM unnest(v_view.cols) WITH ORDINALITY AS u(c, o)
         WHERE v_their[u.o] IS DISTINCT FROM v_ours[u.o] AND v_their[u.o] IS DISTINCT FROM v_base[u.o]
         ORDER BY u.o;
    END LOOP;
END
$$;

COMMENT ON FUNCTION tgsis.merge_attribute_edits(text, bigint, integer[], integer[], integer[]) IS
    'the attributes of a feature (geometry row, feature row) its parent changed since the version''s base and the version did not (both_sides false: to bring into the version), or changed both to other values (both_sides true), as exact text; for the SQL merge by region';

-- internal to the psql merge by region (reached only through the SECURITY DEFINER merge, find_conflicts and
-- resolve functions): not executable by PUBLIC, like tgsis's other internal helpers
REVOKE ALL ON FUNCTION tgsis.merge_attribute_edits(text, bigint, integer[], integer[], integer[]) FROM PUBLIC;
