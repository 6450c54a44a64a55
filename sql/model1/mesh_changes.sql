-- tgsis.mesh_changes(old_geoid, old_revisions, new_geoid, new_revisions, old_seen_in, new_seen_in): every vertex and cell of two meshes, kept, removed or added.
-- The comparison core behind tgsis.geometry_changes and
-- tgsis.geometry_version_changes, with the definitions of
-- tgsis.compare_meshes in the Python client (../shared/spec/mesh-comparison.md):
--   * a new vertex is kept when an old vertex has numerically equal x, y, z
--     (float8 equality: -0.0 = 0.0, one ulp apart differs); the pairing is
--     one-to-one: when a coordinate triple repeats on one side, the k-th
--     old vertex with it (in vrtxid order) pairs with the k-th new one;
--   * a new cell is kept when all its vertices are kept and an old cell has
--     the corresponding old vertices in an even permutation of its order
--     (for segments the same direction; a reversed triangle is not kept),
--     paired one-to-one the same way (in cell id order);
--   * all other old rows are removed, all other new rows added.
-- A side is a geometry read as the session sees it (revisions NULL) or,
-- with a revision set, from the versioned storage with the predicate of
-- tgsis.rows_at, restricted to the geometry's rows by the index (rows_at
-- itself would return every geometry's rows). The stored row versions are
-- named by tgsis.storage_row_versions: <table>_ver, or for a table stored in
-- chunks its decoded chunk versions (the chunk version's revision and
-- lastrevs on each row, the geoid filter on the chunk table's key), read
-- with the same predicate: only that object's chunks are decoded. Both must exist and be
-- static geometries of one geotype other than GEOMETRYCOLLECTION
-- (tgsis.comparable_geometry; seen_in ends its messages).
--
-- Set-based: a hash full join on (x, y, z) pairs the vertices; the new
-- cells are renamed to old vertex ids through the pairs (one hash join per
-- cell corner); a hash full join on (sorted vertex ids, permutation parity)
-- pairs the cells. Those joins are one-to-one exactly when no row is in
-- two pairs, which counts of each side tell; only then (the normal case)
-- are their results used, otherwise the rows are ranked within equal
-- coordinates (or equal cell keys) and joined on the rank too. The ranking
-- branches stand behind one-time filters, so a normal mesh sorts nothing.
CREATE FUNCTION tgsis.mesh_changes(
    p_old_geoid     bigint,
    p_old_revisions integer[],
    p_new_geoid     bigint,
    p_new_revisions integer[],
    p_old_seen_in   text DEFAULT '',
    p_new_seen_in   text DEFAULT '')
RETURNS TABLE (element text, status text, old_id bigint, new_id bigint)
LANGUAGE plpgsql
STABLE
AS $$
DECLARE
    v_old_type text;
    v_new_type text;
    v_table  text;
    v_cellid text;
    v_k      integer;
    v_vrtx   text[];
    v_cells  text[];
    v_filter text;
    v_set    integer[];
    v_key    text;
    v_old    text;
    v_new    text;
    v_cols   text;
    v_keycols text[];
    v_side   integer;
BEGIN
    IF (p_old_revisions IS NOT NULL OR p_new_revisions IS NOT NULL)
       AND (SELECT count(*) FROM tgsis.versioned_tables t
             WHERE t.schemaname = 'tgsis' AND t.tablename IN ('geometry', 'vrtx', 'point', 'segment', 'trgl', 'tetra')) < 6 THEN
        RAISE EXCEPTION 'model 1 is not versioned: there are no versions or revisions of geometry % to compare',
                        coalesce(p_old_geoid::text, 'NULL')
            USING ERRCODE = 'TG100',
                  HINT = 'SELECT tgsis.enable_feature_versioning() versions model 1 and every feature class; tgsis.compare_geometries compares two geometries';
    END IF;
    v_old_type := tgsis.comparable_geometry(p_old_geoid, p_old_revisions, p_old_seen_in);
    v_new_type := tgsis.comparable_geometry(p_new_geoid, p_new_revisions, p_new_seen_in);
    IF v_old_type <> v_new_type THEN
        RAISE EXCEPTION 'cannot compare geometry % (%) with geometry % (%): the geotypes differ',
                        p_old_geoid || p_old_seen_in, v_old_type, p_new_geoid || p_new_seen_in, v_new_type
            USING ERRCODE = 'TG100', HINT = 'compare geometries of one geotype: points, lines, surfaces or tetrahedra';
    END IF;
    v_table := tgsis.simplex_table(v_old_type);
    v_cellid := CASE v_table WHEN 'point' THEN 'pointid' WHEN 'segment' THEN 'segid' WHEN 'trgl' THEN 'trglid'
                             ELSE 'tetraid' END;
    v_k := CASE v_table WHEN 'point' THEN 1 WHEN 'segment' THEN 2 WHEN 'trgl' THEN 3 ELSE 4 END;
    v_keycols := ARRAY(SELECT 's' || i FROM generate_series(1, v_k) AS i) || 'odd'::text;
    -- the rows of each side: parameters $1, $2 (old geoid, revision set) and $3, $4 (new)
    v_cols := (SELECT string_agg(format('v.vrtxid%s', i), ', ') FROM generate_series(1, v_k) AS i);
    FOR v_side IN 1 .. 2 LOOP
        v_set := CASE v_side WHEN 1 THEN p_old_revisions ELSE p_new_revisions END;
        v_filter := CASE WHEN v_set IS NULL THEN format('v.geoid = $%s', 2 * v_side - 1)
                         ELSE format('v.geoid = $%s AND %s', 2 * v_side - 1,
                                     tgsis.visible_versions('v', '$' || 2 * v_side)) END;
        v_vrtx[v_side] := format('SELECT v.vrtxid AS id, v.x, v.y, v.z FROM %s v WHERE %s',
                                 CASE WHEN v_set IS NULL THEN 'tgsis.vrtx' ELSE tgsis.storage_row_versions('tgsis', 'vrtx') END,
                                 v_filter);
        v_cells[v_side] := format('SELECT v.%I AS id, %s FROM %s v WHERE %s', v_cellid, v_cols,
                                  CASE WHEN v_set IS NULL THEN format('tgsis.%I', v_table)
                                       ELSE tgsis.storage_row_versions('tgsis', v_table) END, v_filter);
    END LOOP;

    -- a cell's key: its vertex ids ascending (least/greatest sorting networks) and whether its
    -- order is an odd permutation of them (parity of the number of inversions); %5$s and %6$s
    -- wrap s1, which for a new cell with a vertex that is not kept is NULL, so that it matches nothing
    v_key := CASE v_k
        WHEN 1 THEN '%5$s%1$s%6$s AS s1, false AS odd'
        WHEN 2 THEN '%5$sleast(%1$s, %2$s)%6$s AS s1, greatest(%1$s, %2$s) AS s2, %1$s > %2$s AS odd'
        WHEN 3 THEN '%5$sleast(%1$s, %2$s, %3$s)%6$s AS s1, '
                    'greatest(least(%1$s, %2$s), least(greatest(%1$s, %2$s), %3$s)) AS s2, '
                    'greatest(%1$s, %2$s, %3$s) AS s3, '
                    '((%1$s > %2$s) <> (%1$s > %3$s)) <> (%2$s > %3$s) AS odd'
        ELSE '%5$sleast(%1$s, %2$s, %3$s, %4$s)%6$s AS s1, '
             'least(greatest(least(%1$s, %2$s), least(%3$s, %4$s)), least(greatest(%1$s, %2$s), greatest(%3$s, %4$s))) AS s2, '
             'greatest(greatest(least(%1$s, %2$s), least(%3$s, %4$s)), least(greatest(%1$s, %2$s), greatest(%3$s, %4$s))) AS s3, '
             'greatest(%1$s, %2$s, %3$s, %4$s) AS s4, '
             '((((((%1$s > %2$s) <> (%1$s > %3$s)) <> (%1$s > %4$s)) <> (%2$s > %3$s)) <> (%2$s > %4$s)) <> (%3$s > %4$s)) AS odd'
    END;
    v_old := format(v_key, 'c.vrtxid1', 'c.vrtxid2', 'c.vrtxid3', 'c.vrtxid4', '', '');
    v_new := format(v_key, 'm1.o', 'm2.o', 'm3.o', 'm4.o',
                    format('CASE WHEN %s THEN ',
                           (SELECT string_agg(format('m%s.o IS NOT NULL', i), ' AND ') FROM generate_series(1, v_k) AS i)),
                    ' END');

    RETURN QUERY EXECUTE format($q$
        WITH ov AS NOT MATERIALIZED (%1$s),
             nv AS NOT MATERIALIZED (%2$s),
             -- vertex pairs by equal coordinates, and the vertices of either side without one
             fv AS MATERIALIZED (
                 SELECT ov.id AS o, nv.id AS n FROM ov FULL JOIN nv ON nv.x = ov.x AND nv.y = ov.y AND nv.z = ov.z),
             -- one-to-one unless a coordinate triple repeats on one side (then a row occurs in several pairs)
             vok AS MATERIALIZED (
                 SELECT count(fv.o) = (SELECT count(*) FROM ov) AND count(fv.n) = (SELECT count(*) FROM nv) AS ok FROM fv),
             vm AS MATERIALIZED (
                 SELECT fv.o, fv.n FROM fv WHERE fv.o IS NOT NULL AND fv.n IS NOT NULL AND (SELECT ok FROM vok)
                 UNION ALL
                 SELECT a.id, b.id
                   FROM (SELECT ov.*, row_number() OVER (PARTITION BY ov.x, ov.y, ov.z ORDER BY ov.id) AS r FROM ov) a
                   JOIN (SELECT nv.*, row_number() OVER (PARTITION BY nv.x, nv.y, nv.z ORDER BY nv.id) AS r FROM nv) b
                     ON b.x = a.x AND b.y = a.y AND b.z = a.z AND b.r = a.r
                  WHERE NOT (SELECT ok FROM vok)),
             oc0 AS NOT MATERIALIZED (%3$s),
             nc0 AS NOT MATERIALIZED (%4$s),
             oc AS NOT MATERIALIZED (SELECT c.id, %5$s FROM oc0 c),
             nc AS NOT MATERIALIZED (SELECT c.id, %6$s FROM nc0 c %7$s),
             -- cell pairs by equal keys, and the cells of either side without one
             fc AS MATERIALIZED (SELECT oc.id AS o, nc.id AS n FROM oc FULL JOIN nc ON %8$s),
             cok AS MATERIALIZED (
                 SELECT count(fc.o) = (SELECT count(*) FROM oc0) AND count(fc.n) = (SELECT count(*) FROM nc0) AS ok FROM fc),
             cm AS NOT MATERIALIZED (
                 SELECT fc.o, fc.n FROM fc WHERE fc.o IS NOT NULL AND fc.n IS NOT NULL AND (SELECT ok FROM cok)
                 UNION ALL
                 SELECT a.id, b.id
                   FROM (SELECT oc.*, row_number() OVER (PARTITION BY %9$s ORDER BY oc.id) AS r FROM oc) a
                   JOIN (SELECT nc.*, row_number() OVER (PARTITION BY %10$s ORDER BY nc.id) AS r FROM nc
                          WHERE nc.s1 IS NOT NULL) b
                     ON %11$s AND b.r = a.r
                  WHERE NOT (SELECT ok FROM cok))
        SELECT 'vertex', 'kept', vm.o, vm.n FROM vm
        UNION ALL
        SELECT 'vertex', 'removed', fv.o, NULL FROM fv WHERE fv.n IS NULL AND (SELECT ok FROM vok)
        UNION ALL
        SELECT 'vertex', 'removed', ov.id, NULL FROM ov
         WHERE NOT (SELECT ok FROM vok) AND NOT EXISTS (SELECT FROM vm WHERE vm.o = ov.id)
        UNION ALL
        SELECT 'vertex', 'added', NULL, fv.n FROM fv WHERE fv.o IS NULL AND (SELECT ok FROM vok)
        UNION ALL
        SELECT 'vertex', 'added', NULL, nv.id FROM nv
         WHERE NOT (SELECT ok FROM vok) AND NOT EXISTS (SELECT FROM vm WHERE vm.n = nv.id)
        UNION ALL
        SELECT 'cell', 'kept', cm.o, cm.n FROM cm
        UNION ALL
        SELECT 'cell', 'removed', fc.o, NULL FROM fc WHERE fc.n IS NULL AND (SELECT ok FROM cok)
        UNION ALL
        SELECT 'cell', 'removed', oc0.id, NULL FROM oc0
         WHERE NOT (SELECT ok FROM cok) AND NOT EXISTS (SELECT FROM cm WHERE cm.o = oc0.id)
        UNION ALL
        SELECT 'cell', 'added', NULL, fc.n FROM fc WHERE fc.o IS NULL AND (SELECT ok FROM cok)
        UNION ALL
        SELECT 'cell', 'added', NULL, nc0.id FROM nc0
         WHERE NOT (SELECT ok FROM cok) AND NOT EXISTS (SELECT FROM cm WHERE cm.n = nc0.id)
        $q$,
        v_vrtx[1], v_vrtx[2], v_cells[1], v_cells[2], v_old, v_new,
        (SELECT string_agg(format('LEFT JOIN vm m%1$s ON m%1$s.n = c.vrtxid%1$s', i), ' ') FROM generate_series(1, v_k) AS i),
        (SELECT string_agg(format('nc.%1$s = oc.%1$s', c), ' AND ') FROM unnest(v_keycols) AS c),
        (SELECT string_agg(format('oc.%s', c), ', ') FROM unnest(v_keycols) AS c),
        (SELECT string_agg(format('nc.%s', c), ', ') FROM unnest(v_keycols) AS c),
        (SELECT string_agg(format('b.%1$s = a.%1$s', c), ' AND ') FROM unnest(v_keycols) AS c))
      USING p_old_geoid, p_old_revisions, p_new_geoid, p_new_revisions;
END
$$;

COMMENT ON FUNCTION tgsis.mesh_changes(bigint, integer[], bigint, integer[], text, text) IS
    'comparison core of tgsis.geometry_changes and tgsis.geometry_version_changes: every vertex and cell of an old and a new static geometry of one geotype, each read in the session''s version (revisions NULL) or at a revision set, as (element vertex|cell, status kept|removed|added, old id, new id)';
