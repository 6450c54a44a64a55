-- tgsis.merge_instants_by_slice(version, action, geoid): merge one model-2 feature (a surface at instants) instant by instant in SQL, written into the version; returns the rows written.
-- The psql face of the Python merge of a surface at instants
-- (tgsis.db.merging._merge_sliced_object over tgsis._merge_slices.merge_sliced,
-- docs/merge.md "Models 2 and 3"), which is its oracle, row for row, for the
-- objects whose instants merge by themselves or whose conflicting regions
-- have a parent, child or base solution: an instant (its tgsis.times row,
-- its times_vrtx / times_trgl rows, its vertex and cell property rows keyed
-- (_times, _idx)) added or removed on one side is taken from that side, one
-- only the parent changed (or both alike) is the parent's; one the three
-- states have that the version changed (alone, or both sides differently)
-- is merge3's merge of it (tgsis.merge_instant_by_region: its regions found by
-- tgsis.mesh_merge_work on that instant's rows, the side's rows on each region
-- one side changed, the solution's on a conflicting one, the parent's
-- elsewhere, the version's new ids renumbered); the per-instant feature
-- properties (<class>_pros) column by column. Only the rows whose visibility differs
-- between the three revision sets are read (the keys (instant, id) of rows
-- written or closed since the version was based), then every row of those
-- keys each set sees. The result is written into the VERSION's working
-- revision by a difference keyed by (instant, id), as
-- tgsis.db._state_write.write_sliced_difference writes it (rows gone or
-- differing in their bits closed, new or differing ones inserted copied from
-- the stored row they come from; a property row of no value not written),
-- the geometry row's box and counts follow (tgsis.refresh_geometry), the
-- parent's attribute edits are brought in (as tgsis.merge_mesh_by_region
-- does), the conflict is recorded 'manual'.
-- NULL, nothing written, for an object-level conflict the Python merge
-- leaves unsolved too (an instant removed on one side and changed on the
-- other, added on both sides differently, a per-instant property changed on
-- both sides, attributes changed on both sides, deleted on one side), and
-- for a conflicting region of an instant without a solution: the merge's
-- refusal (TG302) follows. A region solved average or manual takes the rows
-- recorded with its solution (tgsis.merge_instant_by_region, st 8 here).
-- Refused (TG302, nothing written, the hint naming
-- `tgsis version merge NAME`) what only the Python client merges: such a
-- solution recorded with its .npz only, stored regions that are not those
-- of now, an invalid merged instant (tgsis.merge_instant_by_region).
-- p_action 'regions' (tgsis.instants_merge_regions): the analysis alone, nothing written, no right
-- to write asked: 0 with the instants classified in pg_temp.tgsis_ms_slice (the merged ones: in the three
-- states and changed on a side), NULL for an object-level conflict.
-- 42501 for a role that may not
-- read the class or change it, or write the rows the merge writes through
-- their view (tgsis.check_merge_table_write: a property table a DBA took
-- INSERT, UPDATE or DELETE on from the role; SELECT on the per-instant
-- property view, which the Python merge reads), TG002 for one that may not
-- write in the version. extra_float_digits is pinned: values are compared as text, floats
-- exactly.
CREATE FUNCTION tgsis.merge_instants_by_slice(p_version text, p_action text, p_geoid bigint)
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
    v_refused  text := format('%s of version %s refused: feature %s does not merge instant by instant in SQL',
                              p_action, quote_literal(p_version), p_geoid);
    v_hint     text := tgsis.merge_sliced_hint(p_version, p_action, p_geoid, 'instant by instant');
    v_spec     record;
    v_vals     text;
    v_bits     text;
    v_eq       text;
    v_el       text;
    v_why      text;
    v_rev      integer;
    v_settings text[];
    v_written  bigint := 0;
    v_attr     record;
    v_aview    text[] := '{}';
    v_akey     text[] := '{}';
    v_aset     text[] := '{}';
    v_fcols    text[];
    v_pros     tgsis.versioned_tables;
    v_pcols    text[];
    v_gone     text[];
    v_fresh    text[];
    v_count    bigint;
    v_t        float8;
    v_plan     jsonb;
    v_notes    text[] := '{}';
BEGIN
    SELECT * INTO v_sets
      FROM tgsis.merge_sliced_sets(p_version, p_geoid, 'INSTANTS', 'a surface at instants (model 2)', 'instant by instant');
    IF v_sets.p_refused THEN
        RETURN NULL;  -- deleted on one side, attributes changed on both: the Python merge leaves it unsolved too
    END IF;
    v_class := v_sets.p_class;
    v_base := v_sets.p_base;
    v_pset := v_sets.p_parentset;
    v_cset := v_sets.p_versionset;
    v_since := v_sets.p_since;

    -- the work tables: made by the first call of the transaction, emptied by the others (the same relations:
    -- a merge of many objects holds their locks once, not once per object)
    IF pg_catalog.to_regclass('pg_temp.tgsis_ms_spec') IS NULL THEN
        CREATE TEMPORARY TABLE tgsis_ms_spec (tab text, vt tgsis.versioned_tables, okey text, tcol text, idcol text)
            ON COMMIT DROP;
        CREATE TEMPORARY TABLE tgsis_ms_key (tab text, t float8, id bigint) ON COMMIT DROP;
        CREATE TEMPORARY TABLE tgsis_ms_row (tab text, st smallint, t float8, id bigint, vals text[], bits text, eq text,
                                             el text) ON COMMIT DROP;
        CREATE TEMPORARY TABLE tgsis_ms_el (kind text, st smallint, t float8, id bigint, gvals text[], gbits text, geq text,
                                            gel text, pvals text[], pbits text, peq text, nulls text) ON COMMIT DROP;
        CREATE TEMPORARY TABLE tgsis_ms_new (LIKE pg_temp.tgsis_ms_el) ON COMMIT DROP;
        CREATE TEMPORARY TABLE tgsis_ms_slice (t float8, ib boolean, ip boolean, ic boolean, chp boolean, chc boolean,
                                               samepc boolean, src text) ON COMMIT DROP;
        CREATE TEMPORARY TABLE tgsis_ms_prow (t float8, m text[], c text[]) ON COMMIT DROP;
    ELSE
        TRUNCATE pg_temp.tgsis_ms_spec, pg_temp.tgsis_ms_key, pg_temp.tgsis_ms_row, pg_temp.tgsis_ms_el,
                 pg_temp.tgsis_ms_new, pg_temp.tgsis_ms_slice, pg_temp.tgsis_ms_prow;
    END IF;
    -- the tables of a slice: tab T the instants, v / c the vertices / triangles, vp / cp their property rows
    INSERT INTO pg_temp.tgsis_ms_spec
    SELECT s.tab, t AS vt, s.okey, s.tcol, s.idcol
      FROM (VALUES ('T', 'tgsis', 'times', 'geoid', 'times', NULL),
                   ('v', 'tgsis', 'times_vrtx', 'geoid', 'times', 'vrtxid'),
                   ('c', 'tgsis', 'times_trgl', 'geoid', 'times', 'trglid'),
                   ('vp', v_class.schemaname, CASE v_class.proalignment WHEN 'VERTEX' THEN v_class.cellprotable
                                                                       ELSE v_class.otherprotable END, '_geoid', '_times', '_idx'),
                   ('cp', v_class.schemaname, CASE v_class.proalignment WHEN 'CELL' THEN v_class.cellprotable
                                                                      ELSE v_class.otherprotable END, '_geoid', '_times', '_idx'))
           AS s (tab, schemaname, tablename, okey, tcol, idcol)
      JOIN tgsis.versioned_tables t ON t.schemaname = s.schemaname AND t.tablename = s.tablename;

    -- 1. the keys (instant, id) of the rows some set sees otherwise than another; the vertices and triangles
    -- stored in chunks: only the slots of the changed chunks whose values or presence differ between the three
    -- states (tgsis.storage_changed_rows, as tgsis.mesh_merge_work reads an instant's change), not every slot of
    -- a changed chunk (whose property rows were then read too: the instant's whole property table)
    FOR v_spec IN SELECT * FROM pg_temp.tgsis_ms_spec LOOP
        IF v_spec.tab IN ('v', 'c') AND tgsis.stored_in_chunks((v_spec.vt).tablename) THEN
            INSERT INTO pg_temp.tgsis_ms_key
            SELECT v_spec.tab, k.t, k.id
              FROM tgsis.changed_slot_keys(v_spec.vt, v_spec.tcol, v_spec.idcol, v_spec.okey, p_geoid,
                                           v_base, v_pset, v_cset, v_since) AS k;
            CONTINUE;
        END IF;
        INSERT INTO pg_temp.tgsis_ms_key
        SELECT v_spec.tab, r[1]::float8, coalesce(r[2]::bigint, 0)
          FROM tgsis.merge_changed_keys(v_spec.vt, v_spec.okey,
                                        ARRAY[v_spec.tcol] || CASE WHEN v_spec.idcol IS NULL THEN '{}'::text[] ELSE ARRAY[v_spec.idcol] END,
                                        p_geoid, v_since) AS r;
    END LOOP;
    -- an instant added or removed somewhere (its tgsis.times row changed): all its rows, also those no set sees
    -- otherwise (a psql DELETE of the instant's row alone leaves them; the Python writer closes them with it)
    FOR v_spec IN SELECT * FROM pg_temp.tgsis_ms_spec s WHERE s.tab <> 'T' LOOP
        INSERT INTO pg_temp.tgsis_ms_key
        SELECT v_spec.tab, r[1]::float8, r[2]::bigint
          FROM tgsis.storage_run(v_spec.vt, false, format(
                 'SELECT DISTINCT ARRAY[v.%1$I::text, v.%2$I::text] FROM %3$s v
                   WHERE v.%5$I = $1[1]::bigint AND v.%1$I = ANY ($1[2]::float8[])',
                 v_spec.tcol, v_spec.idcol, tgsis.storage_row_versions((v_spec.vt).schemaname, (v_spec.vt).tablename), NULL,
                 v_spec.okey),
               p_1 => ARRAY[v_key, ARRAY(SELECT k.t FROM pg_temp.tgsis_ms_key k WHERE k.tab = 'T')::text]) AS r;
    END LOOP;
    -- a vertex's (a cell's) rows go together: its geometry row and its property row
    INSERT INTO pg_temp.tgsis_ms_key
    SELECT DISTINCT CASE k.tab WHEN 'v' THEN 'vp' WHEN 'vp' THEN 'v' WHEN 'c' THEN 'cp' ELSE 'c' END, k.t, k.id
      FROM pg_temp.tgsis_ms_key k WHERE k.tab <> 'T';
    INSERT INTO pg_temp.tgsis_ms_key SELECT DISTINCT 'T', k.t, 0 FROM pg_temp.tgsis_ms_key k;

    -- 2. their rows as each state sees them (st 1 base, 2 parent, 4 version): the values as text (vals, for
    -- writing; bits: exact, NULL as NaN), eq as tgsis._merge_slices.same_state compares them (floats -0 as 0),
    -- el as merge3 compares an element (a triangle by its oriented key)
    FOR v_spec IN SELECT s.*, (SELECT array_agg(DISTINCT k.t) FROM pg_temp.tgsis_ms_key k WHERE k.tab = s.tab) AS ts,
                         (SELECT array_agg(k.id ORDER BY k.t, k.id) FROM pg_temp.tgsis_ms_key k WHERE k.tab = s.tab) AS ids,
                         (SELECT array_agg(k.t ORDER BY k.t, k.id) FROM pg_temp.tgsis_ms_key k WHERE k.tab = s.tab) AS kts
                    FROM pg_temp.tgsis_ms_spec s LOOP
        CONTINUE WHEN v_spec.ts IS NULL;
        SELECT t.p_vals, t.p_bits, t.p_eq INTO v_vals, v_bits, v_eq
          FROM tgsis.merge_row_texts(format('%I.%I', (v_spec.vt).schemaname, (v_spec.vt).tablename)::regclass,
                                     ARRAY[v_spec.okey, v_spec.tcol, coalesce(v_spec.idcol, v_spec.tcol)]) AS t;
        v_el := CASE v_spec.tab WHEN 'c' THEN 'tgsis.oriented_cell_key(ARRAY[v.vrtxid1, v.vrtxid2, v.vrtxid3])::text'
                                ELSE format('ARRAY[%s]::text[]::text', v_eq) END;
        INSERT INTO pg_temp.tgsis_ms_row
        SELECT v_spec.tab, r[1]::smallint, r[2]::float8, r[3]::bigint, r[4]::text[], r[5], r[6], r[7]
          FROM tgsis.storage_run(v_spec.vt, false, format(
                 'SELECT ARRAY[s.st::text, v.%1$I::text, %2$s, ARRAY[%3$s]::text[]::text,
                               ARRAY[%4$s]::text[]::text, ARRAY[%5$s]::text[]::text, %6$s]
                    FROM %10$s, (VALUES (1, $2), (2, $3), (4, $1[3]::integer[])) AS s (st, revs)
                   WHERE v.%9$I = $1[1]::bigint AND v.%1$I = ANY ($1[2]::float8[])
                     AND v.revision = ANY (s.revs) AND NOT (v.revclosed AND v.lastrevs && s.revs)',
                 v_spec.tcol, CASE WHEN v_spec.idcol IS NULL THEN '''0''' ELSE format('v.%I::text', v_spec.idcol) END, v_vals,
                 v_bits, v_eq, CASE WHEN v_spec.tab = 'T' THEN '''''' ELSE v_el END,
                 NULL, NULL, v_spec.okey,
                 -- (the keys first: each found through the primary key, not by a scan of the instants' rows; stored
                 -- in chunks, the stored versions of only the chunks holding the ids: tgsis.storage_row_versions)
                 CASE WHEN v_spec.idcol IS NULL
                      THEN format('%s v', tgsis.storage_row_versions((v_spec.vt).schemaname, (v_spec.vt).tablename))
                      ELSE format('(SELECT DISTINCT k.t, k.id FROM unnest($1[4]::float8[], $5) AS k (t, id)) AS k
                                   JOIN %s v ON v.%I = k.t AND v.%I = k.id',
                                  tgsis.storage_row_versions((v_spec.vt).schemaname, (v_spec.vt).tablename, v_spec.ids),
                                  v_spec.tcol, v_spec.idcol) END),
               p_1 => ARRAY[v_key, v_spec.ts::text, v_cset::text, v_spec.kts::text], p_2 => v_base,
               p_3 => v_pset, p_5 => v_spec.ids) AS r;
    END LOOP;
    IF EXISTS (SELECT FROM pg_temp.tgsis_ms_row r WHERE r.tab = 'v'
                  AND ('NaN' = ANY (r.vals) OR 'Infinity' = ANY (r.vals) OR '-Infinity' = ANY (r.vals))) THEN
        RAISE EXCEPTION '%: some vertices have non-finite coordinates', v_refused
            USING ERRCODE = 'TG302', HINT = 'correct the coordinates in the version or its parent, or solve it as a whole object: '
                                            || format('SELECT tgsis.resolve_conflict(%L, ''feature'', %L, ''parent''|''child''|''manual'')',
                                                      p_version, v_key);
    END IF;

    -- 3. per element (a vertex or triangle of an instant a state has): its geometry row with its property row
    -- (a missing one reads as NaN: nulls)
    INSERT INTO pg_temp.tgsis_ms_el
    SELECT CASE g.tab WHEN 'v' THEN 'v' ELSE 'c' END AS kind, g.st, g.t, g.id, g.vals AS gvals, g.bits AS gbits,
           g.eq AS geq, g.el AS gel, p.vals AS pvals,
           coalesce(p.bits, n.nulls) AS pbits, coalesce(p.eq, n.nulls) AS peq, n.nulls
      FROM pg_temp.tgsis_ms_row g
      JOIN pg_temp.tgsis_ms_row s ON s.tab = 'T' AND s.st = g.st AND s.t = g.t
      LEFT JOIN pg_temp.tgsis_ms_row p ON p.tab = CASE g.tab WHEN 'v' THEN 'vp' ELSE 'cp' END
                                      AND p.st = g.st AND p.t = g.t AND p.id = g.id
      CROSS JOIN LATERAL (SELECT coalesce(array_fill('NaN'::text, ARRAY[count(*)::integer])::text, '{}') AS nulls
                            FROM pg_catalog.pg_attribute a, pg_temp.tgsis_ms_spec x
                           WHERE x.tab = CASE g.tab WHEN 'v' THEN 'vp' ELSE 'cp' END
                             AND a.attrelid = format('%I.%I', (x.vt).schemaname, (x.vt).tablename)::regclass
                             AND a.attnum > 0 AND NOT a.attisdropped
                             AND a.attname NOT IN ('_geoid', '_times', '_idx')) AS n
     WHERE g.tab IN ('v', 'c');

    -- 4. each instant: which side it is taken from (tgsis._merge_slices._merge_keys): P parent, C version,
    -- M merge3's merge of the version's edit, N none; X an object-level conflict, R both sides changed it
    INSERT INTO pg_temp.tgsis_ms_slice
    WITH sl AS (
        -- (an instant whose rows no state sees, added and removed in later revisions: in none, not NULL)
        SELECT k.t, coalesce(bool_or(r.st = 1), false) AS ib, coalesce(bool_or(r.st = 2), false) AS ip,
               coalesce(bool_or(r.st = 4), false) AS ic
          FROM (SELECT DISTINCT t FROM pg_temp.tgsis_ms_key WHERE tab = 'T') AS k
          LEFT JOIN pg_temp.tgsis_ms_row r ON r.tab = 'T' AND r.t = k.t
         GROUP BY k.t),
    pivot AS (
        SELECT e.kind, e.t, e.id,
               min(e.geq || '|' || e.peq) FILTER (WHERE e.st = 1) AS b,
               min(e.geq || '|' || e.peq) FILTER (WHERE e.st = 2) AS p,
               min(e.geq || '|' || e.peq) FILTER (WHERE e.st = 4) AS c
          FROM pg_temp.tgsis_ms_el e GROUP BY e.kind, e.t, e.id),
    ch AS (
        SELECT s.*,
               s.ib <> s.ip OR EXISTS (SELECT FROM pivot x WHERE x.t = s.t AND x.b IS DISTINCT FROM x.p) AS chp,
               s.ib <> s.ic OR EXISTS (SELECT FROM pivot x WHERE x.t = s.t AND x.b IS DISTINCT FROM x.c) AS chc,
               s.ip = s.ic AND NOT EXISTS (SELECT FROM pivot x WHERE x.t = s.t AND x.p IS DISTINCT FROM x.c) AS samepc
          FROM sl s)
    SELECT ch.*,
           CASE WHEN NOT ch.chc THEN 'P' WHEN NOT ch.chp THEN CASE WHEN ch.ib AND ch.ip AND ch.ic THEN 'M' ELSE 'C' END
                WHEN ch.ib AND NOT ch.ip AND NOT ch.ic THEN 'P'  -- removed on both sides: taken (removed)
                WHEN ch.ib AND NOT (ch.ip AND ch.ic) THEN 'X'
                WHEN ch.samepc THEN 'P'
                WHEN ch.ib THEN 'R'
                ELSE 'X' END AS src
      FROM ch;
    IF EXISTS (SELECT FROM pg_temp.tgsis_ms_slice s WHERE s.src = 'X') THEN
        RETURN NULL;  -- an instant removed on one side and changed on the other, or added on both differently
    END IF;
    -- an instant the three states have that the version changed (M: it alone; R: both sides, differently):
    -- merged by region as merge3 merges it (tgsis.merge_instant_by_region: its regions, the version's rows on
    -- its regions, the parent's elsewhere, the solutions recorded for conflicting ones; so also the rows no
    -- side changed whose bits differ, -0 against 0 or a triangle's vertices rotated, are the region's side's),
    -- its merged rows taken from the states' rows read above (a version's row under its merged id, its
    -- triangles' vertex ids renumbered with it)
    FOR v_t IN SELECT s.t FROM pg_temp.tgsis_ms_slice s WHERE s.src IN ('R', 'M') AND p_action <> 'regions' ORDER BY s.t LOOP
        v_plan := tgsis.merge_instant_by_region(p_version, p_geoid, v_t, v_refused, v_hint);
        IF v_plan IS NULL THEN
            RETURN NULL;  -- a conflicting region without a solution: the merge refuses it (TG302)
        END IF;
        v_notes := v_notes || ARRAY(SELECT n FROM jsonb_array_elements_text(v_plan -> 'notes') AS n);
        INSERT INTO pg_temp.tgsis_ms_new
        SELECT e.kind, e.st, e.t, (x ->> 1)::bigint,
               CASE WHEN jsonb_typeof(x -> 4) = 'array' THEN ARRAY(SELECT jsonb_array_elements_text(x -> 4)) ELSE e.gvals END,
               CASE WHEN jsonb_typeof(x -> 4) = 'array' THEN ARRAY(SELECT jsonb_array_elements_text(x -> 4))::text ELSE e.gbits END,
               e.geq, e.gel, e.pvals, e.pbits, e.peq, e.nulls
          FROM jsonb_array_elements(v_plan -> 'rows') AS x
          JOIN pg_temp.tgsis_ms_el e ON e.kind = x ->> 0 AND e.st = (x ->> 2)::smallint AND e.t = v_t AND e.id = (x ->> 3)::bigint;
        GET DIAGNOSTICS v_count = ROW_COUNT;
        -- the rows of an average or manual solution (st 8): their values as the plan gives them
        INSERT INTO pg_temp.tgsis_ms_new (kind, st, t, id, gvals, gbits, pvals, pbits, nulls)
        SELECT x ->> 0, 8, v_t, (x ->> 1)::bigint, g.g, g.g::text, p.p,
               coalesce(ARRAY(SELECT coalesce(e, 'NaN') FROM unnest(p.p) WITH ORDINALITY AS u(e, o) ORDER BY u.o)::text, n.nulls),
               n.nulls
          FROM jsonb_array_elements(v_plan -> 'rows') AS x
         CROSS JOIN LATERAL (SELECT ARRAY(SELECT jsonb_array_elements_text(x -> 4)) AS g) AS g
         CROSS JOIN LATERAL (SELECT CASE WHEN jsonb_typeof(x -> 5) = 'array'
                                         THEN ARRAY(SELECT CASE WHEN jsonb_typeof(e) = 'null' THEN NULL ELSE e #>> '{}' END
                                                      FROM jsonb_array_elements(x -> 5) WITH ORDINALITY AS u(e, o) ORDER BY u.o)
                                    END AS p) AS p
         CROSS JOIN LATERAL (SELECT coalesce(array_fill('NaN'::text, ARRAY[count(*)::integer])::text, '{}') AS nulls
                               FROM pg_catalog.pg_attribute a, pg_temp.tgsis_ms_spec z
                              WHERE z.tab = CASE x ->> 0 WHEN 'v' THEN 'vp' ELSE 'cp' END
                                AND a.attrelid = format('%I.%I', (z.vt).schemaname, (z.vt).tablename)::regclass
                                AND a.attnum > 0 AND NOT a.attisdropped
                                AND a.attname NOT IN ('_geoid', '_times', '_idx')) AS n
         WHERE x ->> 2 = '8';
        -- and the version's rows (the base's) of the ids no state changed that such a solution rewrites or removes
        INSERT INTO pg_temp.tgsis_ms_el (kind, st, t, id, gbits, pbits, nulls)
        SELECT x ->> 0, 4, v_t, (x ->> 1)::bigint, x ->> 2, x ->> 3, NULL
          FROM jsonb_array_elements(coalesce(v_plan -> 'old', '[]')) AS x;
        IF v_count <> (SELECT count(*) FROM jsonb_array_elements(v_plan -> 'rows') AS x WHERE x ->> 2 <> '8') THEN
            -- (both read the keys that changed: never)
            RAISE EXCEPTION '%: the merged rows of instant % are not among the rows read', v_refused, v_t
                USING ERRCODE = 'XX000';
        END IF;
    END LOOP;

    -- 5. the merged elements of the instants taken from one side: that side's rows (R and M were merged above)
    INSERT INTO pg_temp.tgsis_ms_new
    SELECT e.*
      FROM pg_temp.tgsis_ms_slice s
      JOIN pg_temp.tgsis_ms_el e ON e.t = s.t
     WHERE s.src IN ('P', 'C') AND e.st = CASE s.src WHEN 'P' THEN 2 ELSE 4 END;

    -- 6. the per-instant feature properties (<class>_pros), merged column by column (tgsis._merge_slices._merge_rows)
    SELECT t.* INTO v_pros FROM tgsis.versioned_tables t
     WHERE t.schemaname = v_class.schemaname AND t.tablename = v_class.protablename;
    IF FOUND AND jsonb_array_length(v_class.instant_properties) > 0 THEN
        IF p_action <> 'regions' THEN  -- the Python merge SELECTs the class's view of them (42501 without the right)
            PERFORM tgsis.check_merge_table_write(v_pros, 'SELECT', p_geoid);
        END IF;
        v_pcols := ARRAY(SELECT e ->> 'name' FROM jsonb_array_elements(v_class.instant_properties) AS e);
        FOR v_attr IN SELECT * FROM tgsis.merge_instant_rows(v_pros, p_geoid, ARRAY['_times'], v_pcols,
                                                             v_base, v_pset, v_cset) LOOP
            IF v_attr.conflict THEN
                RETURN NULL;  -- removed on one side and set on the other, or a column changed on both: object-level
            END IF;
            INSERT INTO pg_temp.tgsis_ms_prow VALUES (v_attr.key[1], v_attr.merged, v_attr.version);
        END LOOP;
    END IF;

    IF p_action = 'regions' THEN  -- the analysis only (tgsis.instants_merge_regions reads tgsis_ms_slice): no object-level conflict
        RETURN 0;
    END IF;

    -- the parent's edits of the attributes (geometry row, feature row), as tgsis.merge_mesh_by_region brings them
    SELECT a.p_views, a.p_keys, a.p_sets, a.p_fcols INTO v_aview, v_akey, v_aset, v_fcols
      FROM tgsis.merge_attribute_writes(p_version, p_geoid, v_base, v_pset, v_cset) AS a;

    FOREACH v_why IN ARRAY v_notes LOOP  -- what the solutions discard, said before it is written
        RAISE NOTICE 'feature % of version %: %', p_geoid, quote_literal(p_version), v_why;
    END LOOP;
    -- the rights (to write in the version, to change the class and the feature-row columns the parent changed),
    -- then the session in the version's working revision, the object locked
    SELECT e.p_settings, e.p_revision, e.p_workingset INTO v_settings, v_rev, v_cset
      FROM tgsis.merge_sliced_enter(p_version, p_geoid, v_sets.p_versionid, v_fcols, 'instant by instant') AS e;

    -- 7. the writes, in the version's working revision, as write_sliced_difference writes them: per table, the rows
    -- whose key is gone or whose bits differ closed, then the new and differing ones inserted
    -- the per-instant feature property rows first (as _write_instant_rows: a DELETE, INSERT or UPDATE of the
    -- class's view per instant, which its trigger writes: a row of the working revision in place, any other
    -- closed there and written anew)
    IF v_pcols IS NOT NULL THEN
        FOR v_attr IN SELECT * FROM pg_temp.tgsis_ms_prow r WHERE r.m IS DISTINCT FROM r.c ORDER BY r.t LOOP
            v_written := v_written + tgsis.merge_write_instant_row(v_pros, p_geoid, ARRAY['_times'], ARRAY[v_attr.t::text],
                                                                   v_pcols, v_attr.m, v_attr.c, v_rev, v_cset);
        END LOOP;
    END IF;
    FOR v_spec IN SELECT * FROM pg_temp.tgsis_ms_spec s
                   ORDER BY array_position(ARRAY['T', 'v', 'c', 'vp', 'cp'], s.tab) LOOP
        -- (old: the version's rows; new: the merged; a property row compared as the state holds it, NaN if none;
        -- keys and values flattened as tgsis.merge_write_keyed_rows takes them)
        IF v_spec.tab = 'T' THEN
            SELECT coalesce(array_agg(s.t::text ORDER BY s.t) FILTER (
                                WHERE s.ic AND NOT CASE s.src WHEN 'P' THEN s.ip WHEN 'C' THEN s.ic ELSE true END), '{}'),
                   coalesce(array_agg(s.t::text ORDER BY s.t) FILTER (
                                WHERE NOT s.ic AND CASE s.src WHEN 'P' THEN s.ip WHEN 'C' THEN s.ic ELSE false END), '{}')
              INTO v_gone, v_fresh
              FROM pg_temp.tgsis_ms_slice s;
        ELSE
            SELECT ARRAY(SELECT u.v
                           FROM pg_temp.tgsis_ms_el o CROSS JOIN LATERAL unnest(ARRAY[o.t::text, o.id::text]) WITH ORDINALITY AS u(v, k)
                          WHERE o.st = 4 AND o.kind = left(v_spec.tab, 1)
                            AND NOT EXISTS (SELECT FROM pg_temp.tgsis_ms_new n
                                             WHERE n.kind = o.kind AND n.t = o.t AND n.id = o.id
                                               AND CASE WHEN length(v_spec.tab) = 1 THEN n.gbits = o.gbits ELSE n.pbits = o.pbits END)
                          ORDER BY o.t, o.id, u.k),
                   ARRAY(SELECT u.v
                           FROM pg_temp.tgsis_ms_new n
                          CROSS JOIN LATERAL unnest(ARRAY[n.t::text, n.id::text]
                                                    || CASE WHEN length(v_spec.tab) = 1 THEN n.gvals ELSE n.pvals END)
                                     WITH ORDINALITY AS u(v, k)
                          WHERE n.kind = left(v_spec.tab, 1)
                            AND CASE WHEN length(v_spec.tab) = 1 THEN true ELSE n.pbits <> n.nulls END
                            AND NOT EXISTS (SELECT FROM pg_temp.tgsis_ms_el o
                                             WHERE o.st = 4 AND o.kind = n.kind AND o.t = n.t AND o.id = n.id
                                               AND CASE WHEN length(v_spec.tab) = 1 THEN n.gbits = o.gbits ELSE n.pbits = o.pbits END)
                          ORDER BY n.t, n.id, u.k)
              INTO v_gone, v_fresh;
        END IF;
        v_written := v_written + tgsis.merge_write_keyed_rows(
            v_spec.vt, v_spec.okey, p_geoid,
            ARRAY[v_spec.tcol] || CASE WHEN v_spec.idcol IS NULL THEN '{}'::text[] ELSE ARRAY[v_spec.idcol] END,
            v_gone, v_fresh, v_rev, v_cset,
            CASE WHEN length(v_spec.tab) = 2 THEN v_refused END, v_hint);
    END LOOP;
    PERFORM FROM tgsis.refresh_geometry(p_geoid);
    v_written := v_written + tgsis.merge_apply_attribute_edits(p_geoid, v_aview, v_akey, v_aset, v_fcols,
                                                               v_pset, v_rev, v_cset);
    TRUNCATE pg_temp.tgsis_ms_spec, pg_temp.tgsis_ms_key, pg_temp.tgsis_ms_row, pg_temp.tgsis_ms_el,
             pg_temp.tgsis_ms_new, pg_temp.tgsis_ms_slice, pg_temp.tgsis_ms_prow;
    PERFORM tgsis.merge_sliced_leave(p_version, p_geoid, v_settings, true);
    RETURN v_written;
END
$$;

REVOKE ALL ON FUNCTION tgsis.merge_instants_by_slice(text, text, bigint) FROM PUBLIC;

COMMENT ON FUNCTION tgsis.merge_instants_by_slice(text, text, bigint) IS
    'merge one model-2 feature (a surface at instants) changed both in a version and in its parent instant by instant, in SQL, exactly as the Python merge does: an instant one side added, removed or alone changed taken from it, one the version changed merged by region (merge3: tgsis.merge_instant_by_region, the parent/child/base/average/manual solutions of its conflicting regions), the merged instants written into the version by a difference keyed by (instant, id), the parent''s attribute edits brought in, the conflict recorded manual; NULL for an object-level conflict or an unsolved region (the merge refuses it), TG302 for what only the Python client merges (average or manual solutions recorded with their .npz only); p_action regions: the analysis only; returns the rows written';
