-- tgsis.merge_periods_by_slice(version, action, geoid): merge one model-3 feature (an evolving surface) period by period, geometry instant by geometry instant, in SQL, written into the version; returns the rows written.
-- The psql face of the Python merge of an evolving surface
-- (tgsis.db.merging._merge_sliced_object over tgsis._merge_slices.merge_sliced,
-- docs/merge.md "Models 2 and 3"), which is its oracle, row for row, for the
-- objects whose topology periods and geometry instants were each changed on
-- one side only, or alike on both. A slice is a geometry instant (timem,
-- timet): the period's nodes at their positions there (tgsis.d4dvrtx), the
-- period's triangles (tgsis.d4dtrgl), the property rows keyed (_timem,
-- _timet, _idx). Per period, as merge_sliced decides: added or removed on one
-- side, taken whole from that side; added on both sides alike, taken; else,
-- unless its topology (node ids, triangles) was changed on both sides
-- differently, per geometry instant as tgsis.merge_instants_by_slice decides
-- per instant: taken from the side that changed it, or (the three states have
-- it, only the version changed it) merge3's merge of it (the version's rows of
-- the elements it changed, the parent's elsewhere). The merged geometry
-- instants of a period must share one topology (tgsis._merge_slices.check_periods):
-- else TG308, as the Python merge raises it. The per-instant feature
-- properties (<class>_pros) merge column by column, the parent's attribute
-- edits come along. Only what some revision set sees otherwise than another
-- is read, as each set sees it: a period whose topology instant or geometry
-- instant rows changed (added, removed) whole; elsewhere the nodes and
-- triangles with a row that changed, at every geometry instant of their
-- period (the rows of the others are the same stored rows in the three
-- states: the decisions, the one-topology check and the writes need them
-- not), each looked up by its primary key; d4dvrtx and d4dtrgl stored in
-- chunks give as changed keys only the slots that differ between the three
-- states (tgsis.storage_changed_rows), as tgsis.mesh_merge_work reads them.
-- The result is written into the VERSION's working revision by the Python
-- writer's keyed difference (tgsis.db._state_write.write_sliced_difference:
-- tgsis.timem, timet, node and d4dtrgl from each period's first geometry
-- instant, d4dvrtx and the property rows per geometry instant; rows whose
-- key is gone or whose bits differ closed, new and differing ones inserted,
-- tgsis.merge_write_keyed_rows), the geometry row's box and counts follow
-- (tgsis.refresh_geometry); with more than one period the continuity of the
-- periods is checked (tgsis.check_period_continuity): a merge that breaks it
-- is not written (NULL), as the Python merge leaves it unsolved; the conflict
-- is recorded 'manual'.
-- NULL, nothing written, for an object-level conflict the Python merge
-- leaves unsolved too (a period or geometry instant removed on one side and
-- changed on the other, added on both sides differently, a period's topology
-- changed on both sides differently, a per-instant property changed on both
-- sides, attributes changed on both sides, deleted on one side), and for a
-- conflicting region of a geometry instant without a solution. A geometry
-- instant both sides changed differently (R) merges by its regions, as
-- model 2's instant (tgsis.merge_instant_by_region with p_timem: the region
-- engine on that slice, each region the rows of the side that changed it or
-- of its parent, child or base solution, or the rows recorded with its
-- average or manual solution (the period's nodes at that geometry instant,
-- its triangles, keyed by their ids; checked by tgsis.merge_solution_rows,
-- the merged slice by merge3's validity check), the parent's elsewhere; the
-- discards said in NOTICEs), then the one-topology check (rows no side
-- changed that a solution rewrites or removes, not read at the period's
-- other geometry instants, compared by what the solution does to them: a
-- solution that re-meshes one geometry instant of a period with several is
-- TG308, as in Python). Refused (TG302,
-- nothing written, the hint naming `tgsis version merge NAME`) what only the
-- Python client merges: a region of a geometry instant solved average or
-- manual with its .npz only, a geometry instant whose version's new ids would be renumbered,
-- one only the version changed where a row no side changed differs in its
-- bits between parent and version. p_action 'regions'
-- (tgsis.instants_merge_regions): the analysis alone, nothing written, no
-- right to write asked: 0 with the slices classified in
-- pg_temp.tgsis_mp_slice, NULL for an object-level conflict or when the
-- slices without a conflicting region already give a period two topologies
-- (tgsis._merge_slices.fixed_period_refusal). 42501 for a
-- role that may not read the class, change it or write the rows through
-- their view (tgsis.check_merge_table_write), TG002 for one that may not
-- write in the version. In sql/temporal/ for tgsis.check_period_continuity;
-- tgsis.merge_regions_in_sql calls it through the registry (tgsis.data_models.merge_function). extra_float_digits is pinned:
-- values are compared as text, floats exactly.
CREATE FUNCTION tgsis.merge_periods_by_slice(p_version text, p_action text, p_geoid bigint)
RETURNS bigint
LANGUAGE plpgsql
VOLATILE
SET search_path = pg_catalog, pg_temp
SET extra_float_digits = 1
AS $$
#variable_conflict use_column
DECLARE
    v_key      text := p_geoid::text;
    v_sets     record;
    v_pset     integer[];
    v_class    tgsis.catalog;
    v_base     integer[];
    v_since    integer[];
    v_cset     integer[];
    v_periods  float8[];
    v_whole    float8[] := '{}';
    v_kts      float8[];
    v_refused  text := format('%s of version %s refused: feature %s does not merge period by period in SQL',
                              p_action, quote_literal(p_version), p_geoid);
    v_hint     text := tgsis.merge_sliced_hint(p_version, p_action, p_geoid, 'geometry instant by geometry instant');
    v_spec     record;
    v_vals     text;
    v_bits     text;
    v_eq       text;
    v_why      text;
    v_rev      integer;
    v_settings text[];
    v_written  bigint := 0;
    v_gone     text[];
    v_fresh    text[];
    v_attr     record;
    v_aview    text[] := '{}';
    v_akey     text[] := '{}';
    v_aset     text[] := '{}';
    v_fcols    text[];
    v_pros     tgsis.versioned_tables;
    v_pcols    text[];
    v_plan     jsonb;
    v_notes    text[] := '{}';
    v_count    bigint;
    v_m        float8;
    v_t        float8;
BEGIN
    SELECT * INTO v_sets
      FROM tgsis.merge_sliced_sets(p_version, p_geoid, 'EVOLVING', 'an evolving surface (model 3)', 'period by period');
    IF v_sets.p_refused THEN
        RETURN NULL;  -- deleted on one side, attributes changed on both: the Python merge leaves it unsolved too
    END IF;
    v_class := v_sets.p_class;
    v_base := v_sets.p_base;
    v_pset := v_sets.p_parentset;
    v_cset := v_sets.p_versionset;
    v_since := v_sets.p_since;

    -- the work tables: made by the first call of the transaction, emptied by the others
    IF pg_catalog.to_regclass('pg_temp.tgsis_mp_spec') IS NULL THEN
        -- a table: its key within the object (mcol the period, tcol the geometry instant, idcol the id; NULL: none)
        CREATE TEMPORARY TABLE tgsis_mp_spec (tab text, vt tgsis.versioned_tables, okey text, mcol text, tcol text,
                                              idcol text, keys text[]) ON COMMIT DROP;
        -- a row as a state sees it (st 1 base, 2 parent, 4 version); t -Infinity: a row of the period, id 0: none
        CREATE TEMPORARY TABLE tgsis_mp_row (tab text, st smallint, m float8, t float8, id bigint, vals text[], bits text,
                                             eq text, el text) ON COMMIT DROP;
        CREATE TEMPORARY TABLE tgsis_mp_el (kind text, st smallint, m float8, t float8, id bigint, gvals text[], gbits text,
                                            geq text, gel text, pvals text[], pbits text, peq text, nulls text) ON COMMIT DROP;
        CREATE TEMPORARY TABLE tgsis_mp_new (LIKE pg_temp.tgsis_mp_el) ON COMMIT DROP;
        CREATE TEMPORARY TABLE tgsis_mp_slice (m float8, t float8, ib boolean, ip boolean, ic boolean, chp boolean,
                                               chc boolean, samepc boolean, src text) ON COMMIT DROP;
        CREATE TEMPORARY TABLE tgsis_mp_prow (m float8, t float8, mv text[], cv text[]) ON COMMIT DROP;
        -- the keys (period, id) of a node (kind v) or triangle (c) with a row some set sees otherwise than another
        CREATE TEMPORARY TABLE tgsis_mp_key (kind text, m float8, id bigint) ON COMMIT DROP;
        -- the rows no side changed (not read) that an average or manual solution of a slice rewrites or removes: what
        -- that does to the period's topology (a node: gone or NULL; a triangle: its new node ids or gone)
        CREATE TEMPORARY TABLE tgsis_mp_margin (m float8, t float8, kind text, id bigint, change text) ON COMMIT DROP;
    ELSE
        TRUNCATE pg_temp.tgsis_mp_spec, pg_temp.tgsis_mp_row, pg_temp.tgsis_mp_el, pg_temp.tgsis_mp_new,
                 pg_temp.tgsis_mp_slice, pg_temp.tgsis_mp_prow, pg_temp.tgsis_mp_key, pg_temp.tgsis_mp_margin;
    END IF;
    -- the tables of the model (the registry), in the Python writer's order, then the class's vertex and cell
    -- property rows (vp, cp)
    INSERT INTO pg_temp.tgsis_mp_spec
    SELECT s.tab, t AS vt, s.okey, s.mcol, s.tcol, s.idcol,
           ARRAY[s.mcol] || CASE WHEN s.tcol IS NULL THEN '{}'::text[] ELSE ARRAY[s.tcol] END
                         || CASE WHEN s.idcol IS NULL THEN '{}'::text[] ELSE ARRAY[s.idcol] END
      FROM (SELECT CASE m.tablename WHEN 'timem' THEN 'M' WHEN 'timet' THEN 'T' WHEN 'node' THEN 'n'
                                    WHEN 'd4dtrgl' THEN 'c' WHEN 'd4dvrtx' THEN 'v' END AS tab,
                   'tgsis' AS schemaname, m.tablename, 'geoid' AS okey, 'timem' AS mcol,
                   CASE WHEN m.tablename IN ('timet', 'd4dvrtx') THEN 'timet' END AS tcol,
                   CASE m.tablename WHEN 'node' THEN 'nodeid' WHEN 'd4dvrtx' THEN 'nodeid' WHEN 'd4dtrgl' THEN 'trglid' END AS idcol
              FROM tgsis.model_tables m JOIN tgsis.data_models d ON d.model = m.model AND d.timemodel = 'EVOLVING'
            UNION ALL
            SELECT x.tab, v_class.schemaname, x.tablename, '_geoid', '_timem', '_timet', '_idx'
              FROM (VALUES ('vp', CASE v_class.proalignment WHEN 'VERTEX' THEN v_class.cellprotable ELSE v_class.otherprotable END),
                           ('cp', CASE v_class.proalignment WHEN 'CELL' THEN v_class.cellprotable ELSE v_class.otherprotable END))
                   AS x (tab, tablename)) AS s (tab, schemaname, tablename, okey, mcol, tcol, idcol)
      JOIN tgsis.versioned_tables t ON t.schemaname = s.schemaname AND t.tablename = s.tablename;
    IF (SELECT count(*) FROM pg_temp.tgsis_mp_spec s WHERE length(s.tab) = 1) <> 5 THEN
        RAISE EXCEPTION '%: the model''s tables are not all versioned', v_refused
            USING ERRCODE = 'TG302', HINT = v_hint;
    END IF;

    -- 1. what some set sees otherwise than another (tgsis.db._merge_states: changed_only, read by key as its
    -- ring read does): a period whose topology instant or geometry instant rows changed (added, removed: taken
    -- or dropped whole) is read whole; elsewhere the keys (period, id) of the nodes and triangles whose rows
    -- changed, read at every geometry instant of their period (so that a period's one topology is checked on
    -- them: the rows of the other keys are the same stored rows in the three states); the nodes' positions and the
    -- triangles stored in chunks: only the slots of the changed chunks whose values or presence differ between the
    -- three states (tgsis.storage_changed_rows, as tgsis.mesh_merge_work reads a geometry instant's change), not
    -- every slot of a changed chunk (each then read with its property rows at every geometry instant of the period)
    FOR v_spec IN SELECT * FROM pg_temp.tgsis_mp_spec LOOP
        IF v_spec.tab IN ('v', 'c') AND tgsis.stored_in_chunks((v_spec.vt).tablename) THEN
            INSERT INTO pg_temp.tgsis_mp_key
            SELECT v_spec.tab, k.t, k.id
              FROM tgsis.changed_slot_keys(v_spec.vt, v_spec.mcol, v_spec.idcol, v_spec.okey, p_geoid,
                                           v_base, v_pset, v_cset, v_since) AS k;
        ELSIF v_spec.idcol IS NULL THEN
            v_whole := v_whole || ARRAY(SELECT r[1]::float8
                                          FROM tgsis.merge_changed_keys(v_spec.vt, v_spec.okey, ARRAY[v_spec.mcol], p_geoid,
                                                                        v_since) AS r);
        ELSE
            INSERT INTO pg_temp.tgsis_mp_key
            SELECT CASE WHEN v_spec.tab IN ('c', 'cp') THEN 'c' ELSE 'v' END, r[1]::float8, r[2]::bigint
              FROM tgsis.merge_changed_keys(v_spec.vt, v_spec.okey, ARRAY[v_spec.mcol, v_spec.idcol], p_geoid, v_since) AS r;
        END IF;
    END LOOP;
    v_whole := ARRAY(SELECT DISTINCT p FROM unnest(v_whole) AS p ORDER BY 1);
    DELETE FROM pg_temp.tgsis_mp_key k WHERE k.m = ANY (v_whole);
    v_periods := ARRAY(SELECT p FROM unnest(v_whole) AS p UNION SELECT k.m FROM pg_temp.tgsis_mp_key k ORDER BY 1);

    -- 2. their rows as each state sees them: vals (for writing), bits (exact, NULL as NaN), eq as
    -- tgsis._merge_slices.same_state compares them (floats -0 as 0), el as merge3 compares an element (a triangle
    -- by its oriented key). The geometry instants of the periods first (all of them: few), then per table the
    -- rows of the whole periods and those of the keys, each found through the primary key (period, geometry
    -- instant, id)
    FOR v_spec IN SELECT s.*,
                         (SELECT array_agg(k.m ORDER BY k.m, k.id) FROM (SELECT DISTINCT * FROM pg_temp.tgsis_mp_key) AS k
                           WHERE k.kind = CASE WHEN s.tab IN ('c', 'cp') THEN 'c' ELSE 'v' END) AS kms,
                         (SELECT array_agg(k.id ORDER BY k.m, k.id) FROM (SELECT DISTINCT * FROM pg_temp.tgsis_mp_key) AS k
                           WHERE k.kind = CASE WHEN s.tab IN ('c', 'cp') THEN 'c' ELSE 'v' END) AS kids
                    FROM pg_temp.tgsis_mp_spec s
                   ORDER BY array_position(ARRAY['M', 'T', 'n', 'c', 'v', 'vp', 'cp'], s.tab) LOOP
        EXIT WHEN cardinality(v_periods) = 0;
        CONTINUE WHEN v_spec.tab IN ('M', 'n');  -- (the slices are made of the others, as the Python reader makes them)
        IF v_spec.tcol IS NOT NULL AND v_spec.idcol IS NOT NULL THEN  -- keyed by geometry instant: each key at each
            SELECT array_agg(k.m ORDER BY k.m, g.t, k.id), array_agg(g.t ORDER BY k.m, g.t, k.id),
                   array_agg(k.id ORDER BY k.m, g.t, k.id)
              INTO v_spec.kms, v_kts, v_spec.kids
              FROM (SELECT DISTINCT k.m, k.id FROM unnest(v_spec.kms, v_spec.kids) AS k (m, id)) AS k
              JOIN (SELECT DISTINCT r.m, r.t FROM pg_temp.tgsis_mp_row r WHERE r.tab = 'T') AS g ON g.m = k.m;
        ELSE
            v_kts := NULL;
        END IF;
        SELECT t.p_vals, t.p_bits, t.p_eq INTO v_vals, v_bits, v_eq
          FROM tgsis.merge_row_texts(format('%I.%I', (v_spec.vt).schemaname, (v_spec.vt).tablename)::regclass,
                                     v_spec.okey || v_spec.keys) AS t;
        INSERT INTO pg_temp.tgsis_mp_row
        SELECT v_spec.tab, r[1]::smallint, r[2]::float8, r[3]::float8, r[4]::bigint, r[5]::text[], r[6], r[7], r[8]
          FROM tgsis.storage_run(v_spec.vt, false, format(
                 'SELECT ARRAY[s.st::text, v.%1$I::text, %2$s, %3$s, ARRAY[%4$s]::text[]::text,
                               ARRAY[%5$s]::text[]::text, ARRAY[%6$s]::text[]::text, %7$s]
                    FROM (%8$s) AS v, (VALUES (1, $2), (2, $3), (4, $1[3]::integer[])) AS s (st, revs)
                   WHERE v.revision = ANY (s.revs) AND NOT (v.revclosed AND v.lastrevs && s.revs)',
                 v_spec.mcol,
                 CASE WHEN v_spec.tcol IS NULL THEN '''-Infinity''' ELSE format('v.%I::text', v_spec.tcol) END,
                 CASE WHEN v_spec.idcol IS NULL THEN '''0''' ELSE format('v.%I::text', v_spec.idcol) END,
                 v_vals, v_bits, v_eq,
                 CASE v_spec.tab WHEN 'c' THEN 'tgsis.oriented_cell_key(ARRAY[v.nodeid1, v.nodeid2, v.nodeid3])::text'
                                 ELSE format('ARRAY[%s]::text[]::text', v_eq) END,
                 -- the rows of the whole periods (the geometry instants: of every period read), then those of the keys,
                 -- each key looked up alone (OFFSET 0: not joined to the table as a whole, which a small table invites)
                 -- (stored in chunks, the decoded chunk versions: tgsis.storage_row_versions; for the keys, of only the
                 -- chunks holding their ids)
                 format('SELECT w.* FROM %1$s%2$s w WHERE w.%3$I = $1[1]::bigint AND w.%4$I = ANY ($1[%5$s]::float8[]) %6$s',
                        tgsis.storage_row_versions((v_spec.vt).schemaname, (v_spec.vt).tablename), '', v_spec.okey, v_spec.mcol,
                        CASE WHEN v_spec.idcol IS NULL THEN 2 ELSE 4 END,
                        -- (no whole period: no statement that the planner could answer by a scan of the object)
                        CASE WHEN v_spec.idcol IS NOT NULL AND cardinality(v_whole) = 0 THEN 'AND false' ELSE '' END)
                 || CASE WHEN v_spec.idcol IS NULL THEN '' ELSE format(
                        ' UNION ALL SELECT w.* FROM unnest($1[5]::float8[], $1[6]::float8[], $5) AS k (m, t, id)
                            CROSS JOIN LATERAL (SELECT w.* FROM %1$s%2$s w
                                                 WHERE w.%3$I = $1[1]::bigint AND w.%4$I = k.m %6$s AND w.%5$I = k.id
                                                 OFFSET 0) AS w',
                        tgsis.storage_row_versions((v_spec.vt).schemaname, (v_spec.vt).tablename, coalesce(v_spec.kids, '{}')),
                        '', v_spec.okey, v_spec.mcol, v_spec.idcol,
                        CASE WHEN v_spec.tcol IS NULL THEN '' ELSE format('AND w.%I = k.t', v_spec.tcol) END) END),
               p_1 => ARRAY[v_key, v_periods::text, v_cset::text, v_whole::text, coalesce(v_spec.kms, '{}')::text,
                            coalesce(v_kts, '{}')::text],
               p_2 => v_base, p_3 => v_pset, p_5 => coalesce(v_spec.kids, '{}')) AS r;
    END LOOP;
    ANALYZE pg_temp.tgsis_mp_row;  -- (temporary tables have no statistics otherwise: the joins below want them)
    IF EXISTS (SELECT FROM pg_temp.tgsis_mp_row r WHERE r.tab = 'v'
                  AND ('NaN' = ANY (r.vals) OR 'Infinity' = ANY (r.vals) OR '-Infinity' = ANY (r.vals))) THEN
        RAISE EXCEPTION '%: some nodes have non-finite coordinates', v_refused
            USING ERRCODE = 'TG302', HINT = 'correct the coordinates in the version or its parent, or solve it as a whole object: '
                                            || format('SELECT tgsis.resolve_conflict(%L, ''feature'', %L, ''parent''|''child''|''manual'')',
                                                      p_version, v_key);
    END IF;

    -- 3. per element of a slice a state has (a node at a geometry instant; a triangle of the period at each of its
    -- geometry instants): its geometry row with its property row at that instant (a missing one reads as NaN)
    INSERT INTO pg_temp.tgsis_mp_el
    WITH nulls AS MATERIALIZED (  -- per kind (once: not again per joined row), a property row of no value: one NaN per property column
        SELECT k.kind, coalesce((SELECT array_fill('NaN'::text, ARRAY[count(*)::integer])::text
                                   FROM pg_catalog.pg_attribute a, pg_temp.tgsis_mp_spec x
                                  WHERE x.tab = k.kind || 'p'
                                    AND a.attrelid = format('%I.%I', (x.vt).schemaname, (x.vt).tablename)::regclass
                                    AND a.attnum > 0 AND NOT a.attisdropped AND a.attname <> x.okey
                                    AND a.attname <> ALL (x.keys)), '{}') AS nulls
          FROM (VALUES ('v'), ('c')) AS k (kind))
    SELECT g.tab AS kind, g.st, g.m, s.t, g.id, g.vals, g.bits, g.eq, g.el, p.vals,
           coalesce(p.bits, n.nulls), coalesce(p.eq, n.nulls), n.nulls
      FROM pg_temp.tgsis_mp_row g
      JOIN nulls n ON n.kind = g.tab
      JOIN pg_temp.tgsis_mp_row s ON s.tab = 'T' AND s.st = g.st AND s.m = g.m AND (g.tab = 'c' OR s.t = g.t)
      LEFT JOIN pg_temp.tgsis_mp_row p ON p.tab = g.tab || 'p' AND p.st = g.st AND p.m = g.m AND p.t = s.t AND p.id = g.id;
    ANALYZE pg_temp.tgsis_mp_el;

    -- 4. each geometry instant: which side it is taken from. Per period first (merge_sliced): added or removed on
    -- one side, taken whole from it; added on both, alike or a conflict; its topology changed on both sides
    -- differently, a conflict; then per geometry instant (_merge_keys): P parent, C version, M merge3's merge of the
    -- version's edit; X an object-level conflict, R both sides changed it
    INSERT INTO pg_temp.tgsis_mp_slice
    WITH sl AS (
        SELECT k.m, k.t, bool_or(r.st = 1) AS ib, bool_or(r.st = 2) AS ip, bool_or(r.st = 4) AS ic
          FROM (SELECT DISTINCT m, t FROM pg_temp.tgsis_mp_row WHERE tab = 'T') AS k
          JOIN pg_temp.tgsis_mp_row r ON r.tab = 'T' AND r.m = k.m AND r.t = k.t
         GROUP BY k.m, k.t),
    pivot AS (
        SELECT e.kind, e.m, e.t, e.id,
               min(e.geq || '|' || e.peq) FILTER (WHERE e.st = 1) AS b,
               min(e.geq || '|' || e.peq) FILTER (WHERE e.st = 2) AS p,
               min(e.geq || '|' || e.peq) FILTER (WHERE e.st = 4) AS c
          FROM pg_temp.tgsis_mp_el e GROUP BY e.kind, e.m, e.t, e.id),
    ch AS (
        SELECT s.*,
               s.ib <> s.ip OR EXISTS (SELECT FROM pivot x WHERE x.m = s.m AND x.t = s.t AND x.b IS DISTINCT FROM x.p) AS chp,
               s.ib <> s.ic OR EXISTS (SELECT FROM pivot x WHERE x.m = s.m AND x.t = s.t AND x.b IS DISTINCT FROM x.c) AS chc,
               s.ip = s.ic AND NOT EXISTS (SELECT FROM pivot x WHERE x.m = s.m AND x.t = s.t AND x.p IS DISTINCT FROM x.c) AS samepc
          FROM sl s),
    -- a state's topology of a period: its first geometry instant's node ids and the period's triangles
    topo AS (
        SELECT f.st, f.m,
               coalesce(md5(string_agg(e.kind || e.id || CASE e.kind WHEN 'c' THEN ':' || e.geq ELSE '' END,
                                       ',' ORDER BY e.kind, e.id)), '') AS sig
          FROM (SELECT r.st, r.m, min(r.t) AS t FROM pg_temp.tgsis_mp_row r WHERE r.tab = 'T' GROUP BY r.st, r.m) AS f
          LEFT JOIN pg_temp.tgsis_mp_el e ON e.st = f.st AND e.m = f.m AND e.t = f.t
         GROUP BY f.st, f.m),
    per AS (
        SELECT c.m, bool_or(c.ib) AS pb, bool_or(c.ip) AS pp, bool_or(c.ic) AS pc, bool_or(c.chp) AS chp,
               bool_or(c.chc) AS chc, bool_and(c.samepc) AS samepc
          FROM ch c GROUP BY c.m),
    side AS (
        SELECT p.*,
               CASE WHEN NOT p.chc THEN 'P' WHEN NOT p.chp THEN 'C'
                    WHEN p.pb AND NOT p.pp AND NOT p.pc THEN 'P'  -- removed on both sides: taken (removed)
                    WHEN p.pb AND NOT (p.pp AND p.pc) THEN 'X' ELSE 'B' END AS side,
               (SELECT count(DISTINCT coalesce(t.sig, '')) FROM topo t WHERE t.m = p.m) = 3 AS topo3
          FROM per p)
    SELECT ch.m, ch.t, ch.ib, ch.ip, ch.ic, ch.chp, ch.chc, ch.samepc,
           CASE WHEN s.side = 'X' THEN 'X'
                WHEN s.side <> 'B' AND NOT (s.pb AND s.pp AND s.pc) THEN s.side
                WHEN NOT (s.pb AND s.pp AND s.pc) THEN CASE WHEN s.samepc THEN 'P' ELSE 'X' END
                WHEN s.topo3 THEN 'X'
                WHEN NOT ch.chc THEN 'P' WHEN NOT ch.chp THEN CASE WHEN ch.ib AND ch.ip AND ch.ic THEN 'M' ELSE 'C' END
                WHEN ch.ib AND NOT ch.ip AND NOT ch.ic THEN 'P'  -- removed on both sides: taken (removed)
                WHEN ch.ib AND NOT (ch.ip AND ch.ic) THEN 'X'
                WHEN ch.samepc THEN 'P'
                WHEN ch.ib THEN 'R'
                ELSE 'X' END AS src
      FROM ch JOIN side s ON s.m = ch.m;
    IF EXISTS (SELECT FROM pg_temp.tgsis_mp_slice s WHERE s.src = 'X') THEN
        RETURN NULL;  -- removed on one side and changed on the other, added on both differently, topology on both
    END IF;

    -- a geometry instant both sides changed differently (R): merged by region as merge3 merges it
    -- (tgsis.merge_instant_by_region on that slice, as for an instant of model 2: its regions, each taken from the
    -- side that changed it or from the solution recorded for it, the parent's rows elsewhere); its merged rows
    -- taken from the states' rows read above, the keys the engine did not read (their rows the same stored rows in
    -- the three states) the parent's. A conflicting region without a solution: unsolved (the analysis alone,
    -- p_action 'regions': the slice is left out of the one-topology check, as fixed_period_refusal leaves it out)
    FOR v_m, v_t IN SELECT s.m, s.t FROM pg_temp.tgsis_mp_slice s WHERE s.src = 'R' ORDER BY s.m, s.t LOOP
        v_plan := tgsis.merge_instant_by_region(p_version, p_geoid, v_t, v_refused, v_hint, v_m);
        IF v_plan IS NULL AND p_action = 'regions' THEN
            UPDATE pg_temp.tgsis_mp_slice s SET src = 'U' WHERE s.m = v_m AND s.t = v_t;
            CONTINUE;
        ELSIF v_plan IS NULL THEN
            RETURN NULL;  -- a conflicting region without a solution: the merge refuses it (TG302)
        END IF;
        -- (the version's new ids renumbered: both sides added elements to the period, alike; not merged here)
        SELECT string_agg(format('%s %s', CASE x ->> 0 WHEN 'v' THEN 'node' ELSE 'triangle' END, x ->> 3), ', ')
          INTO v_why
          FROM jsonb_array_elements(v_plan -> 'rows') AS x WHERE x ->> 2 = '4' AND x ->> 1 <> x ->> 3;
        IF v_why IS NOT NULL THEN
            RAISE EXCEPTION '%: the version''s new % at geometry instant % of the period starting at % would be renumbered (merged by the Python client)',
                    v_refused, v_why, v_t, v_m
                USING ERRCODE = 'TG302', HINT = v_hint;
        END IF;
        v_notes := v_notes || ARRAY(SELECT n FROM jsonb_array_elements_text(v_plan -> 'notes') AS n);
        INSERT INTO pg_temp.tgsis_mp_new
        SELECT e.*
          FROM jsonb_array_elements(v_plan -> 'rows') AS x
          JOIN pg_temp.tgsis_mp_el e ON e.kind = x ->> 0 AND e.st = (x ->> 2)::smallint AND e.m = v_m AND e.t = v_t
                                    AND e.id = (x ->> 3)::bigint;
        GET DIAGNOSTICS v_count = ROW_COUNT;
        IF v_count <> (SELECT count(*) FROM jsonb_array_elements(v_plan -> 'rows') AS x WHERE x ->> 2 <> '8') THEN
            -- (both read the keys that changed: never)
            RAISE EXCEPTION '%: the merged rows of geometry instant % of the period starting at % are not among the rows read',
                    v_refused, v_t, v_m
                USING ERRCODE = 'XX000';
        END IF;
        -- the rows of an average or manual solution (st 8): their values as the plan gives them, compared as the
        -- rows read are (a node's coordinates, a triangle's node ids; property rows NaN for none)
        INSERT INTO pg_temp.tgsis_mp_new (kind, st, m, t, id, gvals, gbits, geq, gel, pvals, pbits, peq, nulls)
        SELECT x ->> 0, 8, v_m, v_t, (x ->> 1)::bigint, g.g, g.g::text,
               CASE x ->> 0 WHEN 'v' THEN ARRAY(SELECT (e::float8 + 0::float8)::text FROM unnest(g.g) WITH ORDINALITY AS u(e, o)
                                                 ORDER BY u.o)::text
                            ELSE g.g::text END,
               CASE x ->> 0 WHEN 'c' THEN tgsis.oriented_cell_key(g.g::bigint[])::text END,
               p.p, coalesce(ARRAY(SELECT coalesce(e, 'NaN') FROM unnest(p.p) WITH ORDINALITY AS u(e, o) ORDER BY u.o)::text, n.nulls),
               NULL, n.nulls
          FROM jsonb_array_elements(v_plan -> 'rows') AS x
         CROSS JOIN LATERAL (SELECT ARRAY(SELECT jsonb_array_elements_text(x -> 4)) AS g) AS g
         CROSS JOIN LATERAL (SELECT CASE WHEN jsonb_typeof(x -> 5) = 'array'
                                         THEN ARRAY(SELECT CASE WHEN jsonb_typeof(e) = 'null' THEN NULL ELSE e #>> '{}' END
                                                      FROM jsonb_array_elements(x -> 5) WITH ORDINALITY AS u(e, o) ORDER BY u.o)
                                    END AS p) AS p
         CROSS JOIN LATERAL (SELECT coalesce(array_fill('NaN'::text, ARRAY[count(*)::integer])::text, '{}') AS nulls
                               FROM pg_catalog.pg_attribute a, pg_temp.tgsis_mp_spec z
                              WHERE z.tab = x ->> 0 || 'p'
                                AND a.attrelid = format('%I.%I', (z.vt).schemaname, (z.vt).tablename)::regclass
                                AND a.attnum > 0 AND NOT a.attisdropped AND a.attname <> z.okey
                                AND a.attname <> ALL (z.keys)) AS n
         WHERE x ->> 2 = '8';
        -- and the version's rows (the base's) of the ids no state changed that such a solution rewrites or removes;
        -- those not read (their period not read whole): their rows at the period's other geometry instants are not
        -- known here, so the one-topology check below leaves them out and compares what the solution does to them
        INSERT INTO pg_temp.tgsis_mp_margin
        SELECT v_m, v_t, x ->> 0, (x ->> 1)::bigint,
               CASE WHEN n.id IS NULL THEN 'gone' WHEN x ->> 0 = 'c' THEN n.geq END
          FROM jsonb_array_elements(coalesce(v_plan -> 'old', '[]')) AS x
          LEFT JOIN pg_temp.tgsis_mp_new n ON n.st = 8 AND n.m = v_m AND n.t = v_t AND n.kind = x ->> 0
                                          AND n.id = (x ->> 1)::bigint
         WHERE NOT EXISTS (SELECT FROM pg_temp.tgsis_mp_el e
                            WHERE e.kind = x ->> 0 AND e.st = 4 AND e.m = v_m AND e.t = v_t AND e.id = (x ->> 1)::bigint);
        INSERT INTO pg_temp.tgsis_mp_el (kind, st, m, t, id, gbits, pbits, nulls)
        SELECT x ->> 0, 4, v_m, v_t, (x ->> 1)::bigint, x ->> 2, x ->> 3, NULL
          FROM jsonb_array_elements(coalesce(v_plan -> 'old', '[]')) AS x
         WHERE NOT EXISTS (SELECT FROM pg_temp.tgsis_mp_el e
                            WHERE e.kind = x ->> 0 AND e.st = 4 AND e.m = v_m AND e.t = v_t AND e.id = (x ->> 1)::bigint);
        INSERT INTO pg_temp.tgsis_mp_new
        SELECT e.*
          FROM pg_temp.tgsis_mp_el e
         WHERE e.st = 2 AND e.m = v_m AND e.t = v_t
           AND NOT EXISTS (SELECT FROM jsonb_array_elements(v_plan -> 'rows') AS x WHERE x ->> 0 = e.kind AND (x ->> 1)::bigint = e.id)
           AND NOT EXISTS (SELECT FROM jsonb_array_elements(coalesce(v_plan -> 'old', '[]')) AS x
                            WHERE x ->> 0 = e.kind AND (x ->> 1)::bigint = e.id)
           AND (SELECT count(*) FROM pg_temp.tgsis_mp_el o
                 WHERE o.kind = e.kind AND o.m = e.m AND o.t = e.t AND o.id = e.id
                   AND o.gbits = e.gbits AND o.pbits = e.pbits) = 3;
    END LOOP;

    -- 5. the merged elements: the chosen side's rows (a slice the side lacks: none); M: the version's rows of the
    -- elements it changed (as merge3 compares them), the parent's elsewhere
    INSERT INTO pg_temp.tgsis_mp_new
    WITH pv AS (
        SELECT e.kind, e.m, e.t, e.id,
               min(e.gel || '|' || e.peq) FILTER (WHERE e.st = 1) AS b,
               min(e.gel || '|' || e.peq) FILTER (WHERE e.st = 4) AS c
          FROM pg_temp.tgsis_mp_el e JOIN pg_temp.tgsis_mp_slice s ON s.m = e.m AND s.t = e.t AND s.src = 'M'
         GROUP BY e.kind, e.m, e.t, e.id)
    SELECT e.*
      FROM pg_temp.tgsis_mp_slice s
      JOIN pg_temp.tgsis_mp_el e ON e.m = s.m AND e.t = s.t AND s.src IN ('P', 'C', 'M')
      LEFT JOIN pv ON pv.kind = e.kind AND pv.m = e.m AND pv.t = e.t AND pv.id = e.id
     WHERE e.st = CASE s.src WHEN 'P' THEN 2 WHEN 'C' THEN 4
                             ELSE CASE WHEN pv.b IS DISTINCT FROM pv.c THEN 4 ELSE 2 END END;
    ANALYZE pg_temp.tgsis_mp_new;
    SELECT string_agg(format('%s %s at geometry instant %s of the period starting at %s',
                             CASE pv.kind WHEN 'v' THEN 'node' ELSE 'triangle' END, pv.id, pv.t, pv.m),
                      ', ' ORDER BY pv.m, pv.t, pv.kind DESC, pv.id)
      INTO v_why
      FROM (SELECT e.kind, e.m, e.t, e.id,
                   min(e.gel || '|' || e.peq) FILTER (WHERE e.st = 1) AS b,
                   min(e.gel || '|' || e.peq) FILTER (WHERE e.st = 4) AS c,
                   min(e.gbits || '|' || e.pbits) FILTER (WHERE e.st = 2) AS pbits,
                   min(e.gbits || '|' || e.pbits) FILTER (WHERE e.st = 4) AS cbits
              FROM pg_temp.tgsis_mp_el e JOIN pg_temp.tgsis_mp_slice s ON s.m = e.m AND s.t = e.t AND s.src = 'M'
             GROUP BY e.kind, e.m, e.t, e.id) AS pv
     WHERE pv.b IS NOT DISTINCT FROM pv.c AND pv.pbits IS DISTINCT FROM pv.cbits AND p_action <> 'regions';
    IF v_why IS NOT NULL THEN
        RAISE EXCEPTION '%: rows the version did not change differ in their bits from the parent''s (%): which side''s rows the merge keeps hangs on its regions',
                v_refused, v_why
            USING ERRCODE = 'TG302', HINT = v_hint;
    END IF;
    -- a period has one topology (tgsis._merge_slices.check_periods): the merged geometry instants of each must
    -- have the same nodes and triangles, else the Python merge raises TG308
    SELECT format('feature %s of class %s: merged instant by instant, the topology period starting at %s would have other nodes or triangles at its geometry instant %s than at %s: a period has one topology',
                  p_geoid, v_class.classname, d.m, d.t, d.first)
      INTO v_why
      FROM (SELECT g.m, g.t, first_value(g.t) OVER w AS first, first_value(g.sig) OVER w AS firstsig, g.sig
              FROM (SELECT s.m, s.t,
                           coalesce(md5(string_agg(n.kind || n.id || CASE n.kind WHEN 'c' THEN ':' || n.geq ELSE '' END,
                                                   ',' ORDER BY n.kind, n.id)), '')
                           -- (the rows no side changed a solution rewrote or removed: left out, what it did said)
                           || coalesce((SELECT string_agg(x.kind || x.id || ':' || x.change, ',' ORDER BY x.kind, x.id)
                                          FROM pg_temp.tgsis_mp_margin x
                                         WHERE x.m = s.m AND x.t = s.t AND x.change IS NOT NULL), '') AS sig
                      FROM pg_temp.tgsis_mp_slice s
                      LEFT JOIN pg_temp.tgsis_mp_new n ON n.m = s.m AND n.t = s.t
                                                      AND NOT EXISTS (SELECT FROM pg_temp.tgsis_mp_margin x
                                                                       WHERE x.m = n.m AND x.kind = n.kind AND x.id = n.id)
                     WHERE CASE s.src WHEN 'P' THEN s.ip WHEN 'C' THEN s.ic WHEN 'U' THEN false ELSE true END
                     GROUP BY s.m, s.t) AS g
            WINDOW w AS (PARTITION BY g.m ORDER BY g.t)) AS d
     WHERE d.sig <> d.firstsig
     ORDER BY d.m, d.t LIMIT 1;
    IF v_why IS NOT NULL AND p_action = 'regions' THEN
        RETURN NULL;  -- no solution merges it (tgsis._merge_slices.fixed_period_refusal): no regions
    ELSIF v_why IS NOT NULL THEN
        RAISE EXCEPTION '%', v_why
            USING ERRCODE = 'TG308', HINT = 'tgsis.resolve_conflict solves it as a whole object (parent, child or manual)';
    END IF;

    -- 6. the per-instant feature properties (<class>_pros, keyed (_timem, _timet)), merged column by column
    -- (tgsis._merge_slices._merge_rows)
    SELECT t.* INTO v_pros FROM tgsis.versioned_tables t
     WHERE t.schemaname = v_class.schemaname AND t.tablename = v_class.protablename;
    IF FOUND AND jsonb_array_length(v_class.instant_properties) > 0 THEN
        IF p_action <> 'regions' THEN
            PERFORM tgsis.check_merge_table_write(v_pros, 'SELECT', p_geoid);  -- the Python merge SELECTs the class's view
        END IF;
        v_pcols := ARRAY(SELECT e ->> 'name' FROM jsonb_array_elements(v_class.instant_properties) AS e);
        FOR v_attr IN SELECT * FROM tgsis.merge_instant_rows(v_pros, p_geoid, ARRAY['_timem', '_timet'], v_pcols,
                                                             v_base, v_pset, v_cset) LOOP
            IF v_attr.conflict THEN
                RETURN NULL;  -- removed on one side and set on the other, or a column changed on both: object-level
            END IF;
            INSERT INTO pg_temp.tgsis_mp_prow VALUES (v_attr.key[1], v_attr.key[2], v_attr.merged, v_attr.version);
        END LOOP;
    END IF;

    IF p_action = 'regions' THEN  -- the analysis only (tgsis.instants_merge_regions reads tgsis_mp_slice)
        RETURN 0;
    END IF;
    FOREACH v_why IN ARRAY v_notes LOOP  -- what the solutions discard, said before it is written
        RAISE NOTICE 'feature % of version %: %', p_geoid, quote_literal(p_version), v_why;
    END LOOP;

    -- the parent's edits of the attributes (geometry row, feature row), as tgsis.merge_mesh_by_region brings them
    SELECT a.p_views, a.p_keys, a.p_sets, a.p_fcols INTO v_aview, v_akey, v_aset, v_fcols
      FROM tgsis.merge_attribute_writes(p_version, p_geoid, v_base, v_pset, v_cset) AS a;

    -- the rights (to write in the version, to change the class and the feature-row columns the parent changed),
    -- then the session in the version's working revision, the object locked
    SELECT e.p_settings, e.p_revision, e.p_workingset INTO v_settings, v_rev, v_cset
      FROM tgsis.merge_sliced_enter(p_version, p_geoid, v_sets.p_versionid, v_fcols, 'period by period') AS e;

    -- 7. the writes, in the version's working revision, as write_sliced_difference writes them
    BEGIN  -- (a merge that breaks the periods' continuity is taken back: the Python merge's savepoint)
        -- the per-instant feature property rows first (as _write_instant_rows: a DELETE, INSERT or UPDATE of the
        -- class's view per geometry instant, which its trigger writes)
        IF v_pcols IS NOT NULL THEN
            FOR v_attr IN SELECT * FROM pg_temp.tgsis_mp_prow r WHERE r.mv IS DISTINCT FROM r.cv ORDER BY r.m, r.t LOOP
                v_written := v_written + tgsis.merge_write_instant_row(v_pros, p_geoid, ARRAY['_timem', '_timet'],
                                                                       ARRAY[v_attr.m::text, v_attr.t::text], v_pcols,
                                                                       v_attr.mv, v_attr.cv, v_rev, v_cset);
            END LOOP;
        END IF;
        -- per table, in the Python writer's order: the version's rows (old) against the merged (new), a period's
        -- topology (timem, node, d4dtrgl) from its first geometry instant; rows compared by their bits (a property
        -- row as the state holds it, NaN if none); a property row of no value is not written
        FOR v_spec IN SELECT * FROM pg_temp.tgsis_mp_spec s
                       ORDER BY array_position(ARRAY['M', 'T', 'n', 'c', 'v', 'vp', 'cp'], s.tab) LOOP
            WITH merged AS (  -- the merged slices and the version's
                SELECT s.m, s.t FROM pg_temp.tgsis_mp_slice s WHERE CASE s.src WHEN 'P' THEN s.ip WHEN 'C' THEN s.ic ELSE true END),
            mine AS (SELECT s.m, s.t FROM pg_temp.tgsis_mp_slice s WHERE s.ic),
            firsts AS (SELECT x.m, min(x.t) AS t, 4 AS st FROM mine x GROUP BY x.m
                       UNION ALL SELECT x.m, min(x.t), 0 FROM merged x GROUP BY x.m),
            old AS (
                SELECT e.m, e.t, e.id, e.gbits AS bits, e.gvals AS vals, e.pbits, e.pvals, e.nulls FROM pg_temp.tgsis_mp_el e
                 WHERE e.st = 4 AND e.kind = CASE v_spec.tab WHEN 'n' THEN 'v' ELSE left(v_spec.tab, 1) END
                   AND (v_spec.tab NOT IN ('n', 'c') OR (e.m, e.t, 4) IN (SELECT f.m, f.t, f.st FROM firsts f))),
            new AS (
                SELECT e.m, e.t, e.id, e.gbits AS bits, e.gvals AS vals, e.pbits, e.pvals, e.nulls FROM pg_temp.tgsis_mp_new e
                 WHERE e.kind = CASE v_spec.tab WHEN 'n' THEN 'v' ELSE left(v_spec.tab, 1) END
                   AND (v_spec.tab NOT IN ('n', 'c') OR (e.m, e.t, 0) IN (SELECT f.m, f.t, f.st FROM firsts f))),
            -- the rows of each side as (key, bits, values to write)
            o AS (
                SELECT DISTINCT x.m, '-Infinity'::float8 AS t, 0::bigint AS id, '' AS bits, '{}'::text[] AS vals FROM mine x WHERE v_spec.tab = 'M'
                UNION ALL SELECT x.m, x.t, 0, '', '{}' FROM mine x WHERE v_spec.tab = 'T'
                UNION ALL SELECT e.m, '-Infinity', e.id, CASE v_spec.tab WHEN 'c' THEN e.bits ELSE '' END,
                                 CASE v_spec.tab WHEN 'c' THEN e.vals ELSE '{}' END
                            FROM old e WHERE v_spec.tab IN ('n', 'c')
                UNION ALL SELECT e.m, e.t, e.id, e.bits, e.vals FROM old e WHERE v_spec.tab = 'v'
                UNION ALL SELECT e.m, e.t, e.id, e.pbits, e.pvals FROM old e WHERE length(v_spec.tab) = 2),
            n AS (
                SELECT DISTINCT x.m, '-Infinity'::float8 AS t, 0::bigint AS id, '' AS bits, '{}'::text[] AS vals, false AS novalue
                  FROM merged x WHERE v_spec.tab = 'M'
                UNION ALL SELECT x.m, x.t, 0, '', '{}', false FROM merged x WHERE v_spec.tab = 'T'
                UNION ALL SELECT e.m, '-Infinity', e.id, CASE v_spec.tab WHEN 'c' THEN e.bits ELSE '' END,
                                 CASE v_spec.tab WHEN 'c' THEN e.vals ELSE '{}' END, false
                            FROM new e WHERE v_spec.tab IN ('n', 'c')
                UNION ALL SELECT e.m, e.t, e.id, e.bits, e.vals, false FROM new e WHERE v_spec.tab = 'v'
                UNION ALL SELECT e.m, e.t, e.id, e.pbits, e.pvals, e.pbits = e.nulls FROM new e WHERE length(v_spec.tab) = 2)
            SELECT ARRAY(SELECT u.v
                           FROM o CROSS JOIN LATERAL unnest(ARRAY[o.m::text] || CASE WHEN v_spec.tcol IS NULL THEN '{}'::text[] ELSE ARRAY[o.t::text] END
                                                            || CASE WHEN v_spec.idcol IS NULL THEN '{}'::text[] ELSE ARRAY[o.id::text] END)
                                                     WITH ORDINALITY AS u(v, k)
                          WHERE NOT EXISTS (SELECT FROM n WHERE n.m = o.m AND n.t = o.t AND n.id = o.id
                                                             AND n.bits = o.bits)
                          ORDER BY o.m, o.t, o.id, u.k),
                   ARRAY(SELECT u.v
                           FROM n CROSS JOIN LATERAL unnest(ARRAY[n.m::text] || CASE WHEN v_spec.tcol IS NULL THEN '{}'::text[] ELSE ARRAY[n.t::text] END
                                                            || CASE WHEN v_spec.idcol IS NULL THEN '{}'::text[] ELSE ARRAY[n.id::text] END
                                                            || n.vals)
                                                     WITH ORDINALITY AS u(v, k)
                          WHERE NOT n.novalue
                            AND NOT EXISTS (SELECT FROM o WHERE o.m = n.m AND o.t = n.t AND o.id = n.id
                                                            AND o.bits = n.bits)
                          ORDER BY n.m, n.t, n.id, u.k)
              INTO v_gone, v_fresh;
            v_written := v_written + tgsis.merge_write_keyed_rows(v_spec.vt, v_spec.okey, p_geoid, v_spec.keys, v_gone, v_fresh,
                                                                   v_rev, v_cset, CASE WHEN length(v_spec.tab) = 2 THEN v_refused END,
                                                                   v_hint);
        END LOOP;
        PERFORM FROM tgsis.refresh_geometry(p_geoid);
        v_written := v_written + tgsis.merge_apply_attribute_edits(p_geoid, v_aview, v_akey, v_aset, v_fcols,
                                                                   v_pset, v_rev, v_cset);
        IF (SELECT count(*) FROM tgsis.timem t WHERE t.geoid = p_geoid) > 1 THEN
            PERFORM tgsis.check_period_continuity(p_geoid, NULL, NULL);
        END IF;
    EXCEPTION WHEN SQLSTATE 'TG204' THEN
        PERFORM tgsis.merge_sliced_leave(p_version, p_geoid, v_settings, false);
        RETURN NULL;  -- the periods would not join: the Python merge leaves it unsolved ("its merged rows cannot be written")
    END;
    TRUNCATE pg_temp.tgsis_mp_spec, pg_temp.tgsis_mp_row, pg_temp.tgsis_mp_el, pg_temp.tgsis_mp_new,
             pg_temp.tgsis_mp_slice, pg_temp.tgsis_mp_prow, pg_temp.tgsis_mp_key, pg_temp.tgsis_mp_margin;
    PERFORM tgsis.merge_sliced_leave(p_version, p_geoid, v_settings, true);
    RETURN v_written;
END
$$;

REVOKE ALL ON FUNCTION tgsis.merge_periods_by_slice(text, text, bigint) FROM PUBLIC;

COMMENT ON FUNCTION tgsis.merge_periods_by_slice(text, text, bigint) IS
    'merge one model-3 feature (an evolving surface) changed both in a version and in its parent period by period, geometry instant by geometry instant, in SQL, exactly as the Python merge does, a geometry instant both sides changed by its regions (parent, child, base solutions; average and manual ones by their recorded rows): written into the version by a keyed difference, the parent''s attribute edits brought in, the conflict recorded manual; NULL for an object-level conflict or an unsolved region (the merge refuses it), TG308 for periods whose merged geometry instants would not share one topology, TG302 for what only the Python client merges (average or manual solutions recorded with their .npz only); p_action regions: the analysis only; returns the rows written';
