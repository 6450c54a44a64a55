-- tgsis.merge_mesh_validity(name, k, word, cell table, geoid, base set, refused, hint): refuse a merged mesh of the SQL merge by region that is not valid.
-- tgsis.merge3's checks of a merged state (_check_valid), on the work tables
-- of tgsis.merge_mesh_by_region (pg_temp.tgsis_mr_* of tgsis.mesh_merge_work,
-- tgsis_mw_node / _region / _v / _c), so that SQL refuses exactly the objects
-- the Python merge refuses, saying the same. The merged state is the parent's
-- rows with the rows of the regions taken from the version or the base; only
-- those can break it: near = the vertices of the taken cells, of the parent's
-- cells they replace, and the taken vertices. Refused, in merge3's order:
-- cells on a vertex near the change the merge removes; GOCAD atoms that refer
-- to a vertex it removes (a row as the parent holds it excused only when the parent lacks that vertex
-- too; the parent's atoms the merge keeps as they are judged as well); duplicated cells (the
-- same vertices, any order) or, for triangles and tetrahedra, edges or faces
-- in more than two cells, one of them taken, that no state (base, parent,
-- version) has so often; vertices near the change left without cells, which no
-- state leaves so. The cells on near vertices are the work tables' rows and,
-- for the cells no state changed, the base's rows (one pass over its cells,
-- the vertex columns probed in the few near vertices). TG302 with p_refused
-- and p_hint; nothing is written before. For an instant of a surface at
-- instants (tgsis.merge_instant_by_region: p_table times_trgl, the work
-- tables of that instant) the base's cells of that instant; for a geometry
-- instant of a model-3 period (p_table d4dtrgl) the period's triangles.
CREATE FUNCTION tgsis.merge_mesh_validity(p_name text, p_k integer, p_word text, p_table text, p_geoid bigint,
                                          p_base integer[], p_refused text, p_hint text)
RETURNS void
LANGUAGE plpgsql
VOLATILE
SET search_path = pg_catalog, pg_temp
-- (its statements read work tables sized by the change: compiling them costs more than it saves)
SET jit = off
AS $$
DECLARE
    v_near  bigint[];
    v_bad   bigint[];
    v_badv  bigint[];
    v_keys  text[];
    v_what  text;
    v_limit integer;
    v_msg   text;
BEGIN
    -- the work tables read below, made by tgsis.mesh_merge_work / merge_region_plan and never analyzed: without
    -- statistics the planner took them for a few rows and joined them by nested loops (rows x rows)
    ANALYZE pg_temp.tgsis_mw_v;
    ANALYZE pg_temp.tgsis_mw_c;
    ANALYZE pg_temp.tgsis_mr_margin;
    -- the rows taken from the version or the base (a parent-only merge is the parent's valid state)
    CREATE TEMPORARY TABLE tgsis_mw_drop ON COMMIT DROP AS
    SELECT n.kind, n.id FROM pg_temp.tgsis_mw_node n JOIN pg_temp.tgsis_mw_region g USING (region) WHERE g.src IN (1, 4, 8)
    -- (the new ids of an average or manual solution: taken too)
    UNION SELECT 'v', n.id FROM pg_temp.tgsis_mw_v n WHERE n.src = 8 AND n.present
    UNION SELECT 'c', n.id FROM pg_temp.tgsis_mw_c n WHERE n.src = 8 AND n.present;
    IF NOT EXISTS (SELECT FROM pg_temp.tgsis_mw_drop) THEN
        RETURN;
    END IF;
    -- the merged state's taken cells, and the parent's cells of those ids (a cell no state changed: its one row)
    CREATE TEMPORARY TABLE tgsis_mw_taken ON COMMIT DROP AS
    SELECT d.id, coalesce(c.v, g.v) AS v
      FROM pg_temp.tgsis_mw_drop d
      LEFT JOIN pg_temp.tgsis_mw_c c ON c.id = d.id
      LEFT JOIN pg_temp.tgsis_mr_margin g ON g.id = d.id
     WHERE d.kind = 'c' AND (c.present OR (c.id IS NULL AND g.id IS NOT NULL));
    v_near := ARRAY(SELECT unnest(t.v) FROM pg_temp.tgsis_mw_taken t
                    UNION SELECT unnest(coalesce(p.v, g.v))
                            FROM pg_temp.tgsis_mw_drop d
                            LEFT JOIN pg_temp.tgsis_mr_c p ON p.id = d.id AND p.st = 2
                            LEFT JOIN pg_temp.tgsis_mr_margin g ON g.id = d.id
                                  AND NOT EXISTS (SELECT FROM pg_temp.tgsis_mr_c c WHERE c.id = d.id)
                           WHERE d.kind = 'c'
                    UNION SELECT d.id FROM pg_temp.tgsis_mw_drop d WHERE d.kind = 'v');
    -- the near vertices, in which state each is (st 1 base, 2 parent, 4 version, 8 merged; one no state
    -- changed is in all or none: tgsis_mr_vb holds the base's)
    -- (joins to each work table grouped once by id, not an EXISTS per near vertex in the select list: a
    -- correlated subplan scanned tgsis_mr_vb and tgsis_mw_v once per near vertex)
    CREATE TEMPORARY TABLE tgsis_mw_nearv ON COMMIT DROP AS
    SELECT u.id,
           CASE WHEN m.id IS NULL
                THEN CASE WHEN b.id IS NOT NULL
                          -- (one a solution removes: in the three states, not in the merged one)
                          THEN CASE WHEN coalesce(n.absent, false) THEN 7 ELSE 15 END
                          WHEN coalesce(n.present, false) THEN 8  -- a solution's new id
                          ELSE 0 END
                ELSE m.st + CASE WHEN coalesce(n.present, false) THEN 8 ELSE 0 END
           END AS st
      FROM unnest(v_near) AS u(id)
      -- the states of each near vertex some state changed, grouped once (not a scan of the work table per vertex)
      LEFT JOIN (SELECT m.id, sum(DISTINCT m.st) AS st FROM pg_temp.tgsis_mr_v m GROUP BY m.id) AS m ON m.id = u.id
      LEFT JOIN (SELECT DISTINCT b.id FROM pg_temp.tgsis_mr_vb b) AS b ON b.id = u.id
      LEFT JOIN (SELECT n.id, bool_or(n.present) AS present, bool_or(NOT n.present) AS absent
                   FROM pg_temp.tgsis_mw_v n GROUP BY n.id) AS n ON n.id = u.id;
    ANALYZE pg_temp.tgsis_mw_nearv;
    -- each state's cells on a near vertex: the work tables' rows, and the base's rows of the cells no state changed
    CREATE TEMPORARY TABLE tgsis_mw_local (st smallint NOT NULL, id bigint NOT NULL, v bigint[] NOT NULL) ON COMMIT DROP;
    EXECUTE format('INSERT INTO pg_temp.tgsis_mw_local
                    SELECT s.st, c.id, c.v
                      FROM (SELECT v.%1$I AS id, %2$s AS v FROM %3$s v
                             WHERE v.geoid = $1 AND v.revision = ANY ($2) AND NOT (v.revclosed AND v.lastrevs && $2)
                               AND %4$s%5$s) AS c,
                           (VALUES (1::smallint), (2), (4), (8)) AS s (st)
                     WHERE NOT EXISTS (SELECT FROM pg_temp.tgsis_mr_c m WHERE m.id = c.id)',
                   CASE p_table WHEN 'point' THEN 'pointid' WHEN 'segment' THEN 'segid' WHEN 'trgl' THEN 'trglid'
                                WHEN 'times_trgl' THEN 'trglid' WHEN 'd4dtrgl' THEN 'trglid' ELSE 'tetraid' END,
                   format('ARRAY[%s]', (SELECT string_agg(format('v.vrtxid%s', i), ', ' ORDER BY i) FROM generate_series(1, p_k) AS i)),
                   CASE WHEN p_table = 'd4dtrgl'  -- (a model-3 period's triangles: node columns named as vertex columns;
                                                  -- stored in chunks, their decoded chunk versions, not the chunk table)
                        THEN format('(SELECT w.geoid, w.timem, w.trglid, w.nodeid1 AS vrtxid1, w.nodeid2 AS vrtxid2,
                                             w.nodeid3 AS vrtxid3, w.revision, w.revclosed, w.lastrevs FROM %s w)',
                                    tgsis.storage_row_versions('tgsis', p_table))
                        -- (stored in chunks: only the chunks whose vertex-id bounds hold a near vertex)
                        ELSE tgsis.storage_cells_on(p_table, v_near) END,
                   -- the cells on a near vertex through the vertex BRIN, by spans (an = ANY searches it once per id)
                   tgsis.cells_on_vertices_sql(p_k, v_near, '$3'),
                   -- (an instant of a surface at instants, tgsis.merge_instant_by_region: that instant's cells)
                   -- (a geometry instant of a model-3 period: the period's triangles)
                   CASE WHEN p_table = 'd4dtrgl' THEN ' AND v.timem = $5'
                        WHEN (SELECT i.times FROM pg_temp.tgsis_mr_info i) IS NOT NULL THEN ' AND v.times = $4' ELSE '' END)
      USING p_geoid, p_base, v_near, (SELECT i.times FROM pg_temp.tgsis_mr_info i),
            (SELECT i.timem FROM pg_temp.tgsis_mr_info i);
    -- a cell no state changed that a solution rewrites or removes (a margin cell) is its row in the merged state
    DELETE FROM pg_temp.tgsis_mw_local l WHERE l.st = 8 AND EXISTS (SELECT FROM pg_temp.tgsis_mw_c n WHERE n.id = l.id);
    INSERT INTO pg_temp.tgsis_mw_local
    SELECT m.st, m.id, m.v FROM pg_temp.tgsis_mr_c m WHERE m.v && v_near
    UNION ALL
    SELECT 8, n.id, n.v FROM pg_temp.tgsis_mw_c n WHERE n.present AND n.v && v_near;
    ANALYZE pg_temp.tgsis_mw_local;

    -- cells the merge keeps on vertices it removes
    v_bad := ARRAY(SELECT l.id FROM pg_temp.tgsis_mw_local l
                    WHERE l.st = 8 AND EXISTS (SELECT FROM pg_temp.tgsis_mw_nearv x WHERE x.id = ANY (l.v) AND x.st & 8 = 0)
                    ORDER BY l.id);
    IF cardinality(v_bad) > 0 THEN
        v_badv := ARRAY(SELECT DISTINCT x.id FROM pg_temp.tgsis_mw_local l JOIN pg_temp.tgsis_mw_nearv x ON x.id = ANY (l.v)
                         WHERE l.st = 8 AND l.id = ANY (v_bad) AND x.st & 8 = 0 ORDER BY x.id);
        RAISE EXCEPTION '%: invalid merge: %: the merge would keep %s % on vertices % that it removes', p_refused, p_name,
                p_word, tgsis.merge_ids_text(v_bad::text[]), tgsis.merge_ids_text(v_badv::text[])
            USING ERRCODE = 'TG302', DETAIL = 'one side removed vertices the other side''s cells use: solve the region with one side''s rows',
                  HINT = p_hint;
    END IF;

    -- atoms (refid) that refer to vertices the merge removes (a vertex row the parent holds so is excused when the
    -- parent lacks the vertex too): of the rows the merge writes, and of the parent's atoms it keeps as they are
    -- (the base's of a vertex no state changed) that refer to a vertex the parent has and the merge removes
    CREATE TEMPORARY TABLE tgsis_mw_atombad (id bigint NOT NULL, ref bigint NOT NULL) ON COMMIT DROP;
    v_badv := ARRAY(SELECT DISTINCT n.ref FROM pg_temp.tgsis_mw_v n
                     WHERE n.present AND n.ref IS NOT NULL
                       AND NOT EXISTS (SELECT FROM pg_temp.tgsis_mw_v r WHERE r.id = n.ref AND r.present)
                       AND (EXISTS (SELECT FROM pg_temp.tgsis_mr_v r WHERE r.id = n.ref)
                            OR EXISTS (SELECT FROM pg_temp.tgsis_mw_v r WHERE r.id = n.ref AND NOT r.present)));
    IF cardinality(v_badv) > 0 THEN  -- refs no state changed are there when the base has them (and no solution removes them)
        INSERT INTO pg_temp.tgsis_mw_atombad
        SELECT n.id, n.ref FROM pg_temp.tgsis_mw_v n
         WHERE n.present AND n.ref = ANY (v_badv)
           AND NOT (EXISTS (SELECT FROM pg_temp.tgsis_mr_v p
                             WHERE p.id = n.id AND p.st = 2 AND p.x = n.x AND p.y = n.y AND p.z = n.z
                               AND 'NaN'::float8 NOT IN (n.x, n.y, n.z)
                               AND p.val IS NOT DISTINCT FROM n.val AND p.ref IS NOT DISTINCT FROM n.ref)
                    -- (the parent lacks the vertex too: a side's change of it, or a row no state changed)
                    AND NOT (EXISTS (SELECT FROM pg_temp.tgsis_mr_v r WHERE r.id = n.ref AND r.st = 2)
                             OR NOT EXISTS (SELECT FROM pg_temp.tgsis_mr_v r WHERE r.id = n.ref)));
    END IF;
    v_badv := ARRAY(SELECT x.id FROM pg_temp.tgsis_mw_nearv x WHERE x.st & 8 = 0 AND x.st & 2 <> 0);
    IF cardinality(v_badv) > 0 THEN  -- vertices the parent has and the merge removes: the parent's atoms on them
        -- (a vertex the merge writes was judged above; one it removes takes its atom along)
        EXECUTE format('INSERT INTO pg_temp.tgsis_mw_atombad
                        SELECT k.id, k.ref
                          FROM (SELECT a.vrtxid AS id, a.refid AS ref FROM %s a
                                 WHERE a.geoid = $1 AND a.revision = ANY ($2) AND NOT (a.revclosed AND a.lastrevs && $2)
                                   AND a.refid = ANY ($3)
                                   AND NOT EXISTS (SELECT FROM pg_temp.tgsis_mr_v m WHERE m.id = a.vrtxid)
                                UNION
                                SELECT m.id, m.ref FROM pg_temp.tgsis_mr_v m WHERE m.st = 2 AND m.ref = ANY ($3)) AS k
                         WHERE NOT EXISTS (SELECT FROM pg_temp.tgsis_mw_v n WHERE n.id = k.id)
                           AND NOT EXISTS (SELECT FROM pg_temp.tgsis_mw_nearv x WHERE x.id = k.id AND x.st & 8 = 0)',
                       tgsis.storage_table('tgsis', 'atom'))
          USING p_geoid, p_base, v_badv;
    END IF;
    IF EXISTS (SELECT FROM pg_temp.tgsis_mw_atombad) THEN
        v_bad := ARRAY(SELECT DISTINCT b.id FROM pg_temp.tgsis_mw_atombad b ORDER BY b.id);
        v_badv := ARRAY(SELECT DISTINCT b.ref FROM pg_temp.tgsis_mw_atombad b ORDER BY b.ref);
        RAISE EXCEPTION '%: invalid merge: %: the merge would keep vertices %, atoms (refid) that refer to vertices %, which it removes',
                p_refused, p_name, tgsis.merge_ids_text(v_bad::text[]), tgsis.merge_ids_text(v_badv::text[])
            USING ERRCODE = 'TG302',
                  DETAIL = 'one side removed vertices the other side''s atoms refer to: solve the region with one side''s rows',
                  HINT = p_hint;
    END IF;

    -- duplicated cells (the same vertices), then edges of triangles / faces of tetrahedra in more than two cells:
    -- a key held more often than the limit, by a taken cell among others, that no state holds so often
    CREATE TEMPORARY TABLE tgsis_mw_keys (st smallint NOT NULL, kind integer NOT NULL, id bigint NOT NULL, k bigint[] NOT NULL)
        ON COMMIT DROP;
    INSERT INTO pg_temp.tgsis_mw_keys
    SELECT l.st, 1, l.id, ARRAY(SELECT x FROM unnest(l.v) AS x ORDER BY x) FROM pg_temp.tgsis_mw_local l;
    IF p_k >= 3 THEN  -- a cell's edges / faces: its sorted vertices but one (a sorted array less one element is sorted)
        INSERT INTO pg_temp.tgsis_mw_keys
        SELECT q.st, 2, q.id, q.k[1:i - 1] || q.k[i + 1:p_k]
          FROM pg_temp.tgsis_mw_keys q, generate_series(1, p_k) AS i
         WHERE q.kind = 1;
    END IF;
    ANALYZE pg_temp.tgsis_mw_keys;
    FOR v_limit, v_what IN SELECT 1, format('duplicated %ss (the same vertices)', p_word)
                           UNION ALL SELECT 2, format('non-manifold %ss (in more than two %ss)',
                                                      CASE p_k WHEN 3 THEN 'edge' ELSE 'face' END, p_word)
                            WHERE p_k >= 3 ORDER BY 1 LOOP
        -- (the keys some state holds so often, grouped once: not a scan of the keys per merged key)
        v_keys := ARRAY(
            WITH often AS MATERIALIZED (
                SELECT DISTINCT s.k FROM pg_temp.tgsis_mw_keys s WHERE s.st IN (1, 2, 4) AND s.kind = v_limit
                 GROUP BY s.st, s.k HAVING count(*) > v_limit)
            SELECT format('(%s%s)', array_to_string(o.k, ', '), CASE WHEN cardinality(o.k) = 1 THEN ',' ELSE '' END)
              FROM (SELECT q.k FROM pg_temp.tgsis_mw_keys q WHERE q.st = 8 AND q.kind = v_limit
                     GROUP BY q.k HAVING count(*) > v_limit
                       AND bool_or(q.id IN (SELECT t.id FROM pg_temp.tgsis_mw_taken t))) AS o
             WHERE NOT EXISTS (SELECT FROM often s WHERE s.k = o.k)
             ORDER BY o.k);
        IF cardinality(v_keys) > 0 THEN
            v_bad := ARRAY(SELECT DISTINCT q.id FROM pg_temp.tgsis_mw_keys q
                            WHERE q.st = 8 AND q.kind = v_limit
                              AND format('(%s%s)', array_to_string(q.k, ', '), CASE WHEN cardinality(q.k) = 1 THEN ',' ELSE '' END) = ANY (v_keys)
                            ORDER BY q.id);
            RAISE EXCEPTION '%: invalid merge: %: the merge would make % that no state has: vertex ids %, cells %', p_refused,
                    p_name, v_what, tgsis.merge_ids_text(v_keys), tgsis.merge_ids_text(v_bad::text[])
                USING ERRCODE = 'TG302', DETAIL = 'solve the region with one side''s rows', HINT = p_hint;
        END IF;
    END LOOP;

    -- vertices near the change left without cells, which no state leaves so
    -- (per vertex, the states that have a cell on it: one pass over the cells' corners, joined by id, not a
    -- scan of the cells per near vertex)
    v_badv := ARRAY(SELECT x.id FROM pg_temp.tgsis_mw_nearv x
                      LEFT JOIN (SELECT u.vid, bit_or(l.st::integer) AS sts
                                   FROM pg_temp.tgsis_mw_local l CROSS JOIN LATERAL unnest(l.v) AS u (vid)
                                  GROUP BY u.vid) AS c ON c.vid = x.id
                     WHERE x.st & 8 <> 0
                       AND coalesce(c.sts, 0) & 8 = 0
                       -- (every state of base, parent, version that has the vertex has a cell on it)
                       AND (x.st & 7) & ~coalesce(c.sts, 0) = 0
                     ORDER BY x.id);
    IF cardinality(v_badv) > 0 THEN
        RAISE EXCEPTION '%: invalid merge: %: the merge would leave vertices % without %s, which no state does', p_refused,
                p_name, tgsis.merge_ids_text(v_badv::text[]), p_word
            USING ERRCODE = 'TG302', DETAIL = 'solve the region with one side''s rows', HINT = p_hint;
    END IF;
END
$$;

COMMENT ON FUNCTION tgsis.merge_mesh_validity(text, integer, text, text, bigint, integer[], text, text) IS
    'refuse (TG302) the merged mesh of the SQL merge by region (work tables of tgsis.merge_mesh_by_region) that tgsis.merge3 refuses: cells on removed vertices, duplicated cells or non-manifold edges/faces no state has, vertices left without cells';

-- internal to the merges: reached only through the SECURITY DEFINER merge, refresh, find_conflicts and
-- resolve functions, as their owner; not executable by PUBLIC (tests/test_function_grants.py)
REVOKE ALL ON FUNCTION tgsis.merge_mesh_validity(text, integer, text, text, bigint, integer[], text, text) FROM PUBLIC;
