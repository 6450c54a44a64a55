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
    v_version  tgsis.versions;
    v_parent   tgsis.versions;
    v_class    tgsis.catalog;
    v_base     integer[];
    v_since    integer[];
    v_cset     integer[];
    v_refused  text := format('%s of version %s refused: feature %s does not merge instant by instant in SQL',
                              p_action, quote_literal(p_version), p_geoid);
    v_hint     text := format('`tgsis version %s %s` or tgsis.%s_version(conn, %s) in Python merges it instant by instant '
                              '(its regions); else solve it as a whole object: '
                              'SELECT tgsis.resolve_conflict(%L, ''feature'', %L, ''parent''|''child''|''manual'')',
                              p_action, tgsis.shell_quote(p_version), p_action, pg_catalog.to_json(p_version)::text, p_version, p_geoid::text);
    v_spec     record;
    v_vals     text;
    v_eq       text;
    v_el       text;
    v_why      text;
    v_rev      integer;
    v_settings text[];
    v_written  bigint := 0;
    v_count    bigint;
    v_times    float8[];
    v_ids      bigint[];
    v_flat     text[];
    v_width    integer;
    v_cols     text;
    v_casts    text;
    v_attr     record;
    v_aview    text[] := '{}';
    v_akey     text[] := '{}';
    v_aset     text[] := '{}';
    v_fcols    text[];
    v_pros     tgsis.versioned_tables;
    v_pcols    text[];
    v_t        float8;
    v_plan     jsonb;
    v_notes    text[] := '{}';
BEGIN
    SELECT * INTO v_version FROM tgsis.versions WHERE versionid = tgsis.version_id(p_version);
    SELECT * INTO v_parent FROM tgsis.versions WHERE versionid = v_version.parentid;
    SELECT c.* INTO v_class FROM tgsis.catalog c WHERE c.classname = tgsis.class_of_geoid(p_geoid);
    IF v_class.timemodel IS DISTINCT FROM 'INSTANTS' THEN
        RAISE EXCEPTION 'feature % is not a surface at instants (model 2)', p_geoid
            USING ERRCODE = 'TG100', HINT = format('SELECT tgsis.merge_version(%L) merges it as its model merges', p_version);
    END IF;
    IF p_geoid IN (SELECT tgsis.class_denied_geoids('SELECT')) THEN
        RAISE EXCEPTION 'role % may not read feature % (its class): it cannot be merged instant by instant',
                quote_ident(tgsis.calling_role()), p_geoid
            USING ERRCODE = '42501', HINT = 'the class''s owner can GRANT SELECT on its feature table';
    END IF;
    IF tgsis.object_merge_refusal(p_version, p_geoid) IS NOT NULL THEN
        RETURN NULL;  -- deleted on one side, attributes changed on both: the Python merge leaves it unsolved too
    END IF;
    v_base := tgsis.revision_set(v_version.versionid, v_version.initrevision);
    v_cset := v_version.workingset;
    v_since := ARRAY(SELECT r FROM unnest(v_base || v_parent.workingset || v_cset) AS r
                     EXCEPT SELECT r FROM unnest(v_base) AS r WHERE r = ANY (v_parent.workingset) AND r = ANY (v_cset)
                     ORDER BY 1);

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
        CREATE TEMPORARY TABLE tgsis_ms_pros (st smallint, t float8, vals text[]) ON COMMIT DROP;
        CREATE TEMPORARY TABLE tgsis_ms_prow (t float8, m text[], c text[]) ON COMMIT DROP;
    ELSE
        TRUNCATE pg_temp.tgsis_ms_spec, pg_temp.tgsis_ms_key, pg_temp.tgsis_ms_row, pg_temp.tgsis_ms_el,
                 pg_temp.tgsis_ms_new, pg_temp.tgsis_ms_slice, pg_temp.tgsis_ms_pros, pg_temp.tgsis_ms_prow;
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

    -- 1. the keys (instant, id) of the rows some set sees otherwise than another
    FOR v_spec IN SELECT * FROM pg_temp.tgsis_ms_spec LOOP
        INSERT INTO pg_temp.tgsis_ms_key
        SELECT v_spec.tab, r[1]::float8, r[2]::bigint
          FROM tgsis.storage_run(v_spec.vt, false, format(
                 'SELECT DISTINCT ARRAY[v.%I::text, %s] FROM %I.%I v WHERE v.%I = $1[1]::bigint
                     AND (v.revision = ANY ($2) OR (v.revclosed AND v.lastrevs && $2))',
                 v_spec.tcol, CASE WHEN v_spec.idcol IS NULL THEN '''0''' ELSE format('v.%I::text', v_spec.idcol) END, (v_spec.vt).schemaname,
                 (v_spec.vt).tablename || '_ver', v_spec.okey),
               p_1 => ARRAY[v_key], p_2 => v_since) AS r;
    END LOOP;
    -- an instant added or removed somewhere (its tgsis.times row changed): all its rows, also those no set sees
    -- otherwise (a psql DELETE of the instant's row alone leaves them; the Python writer closes them with it)
    FOR v_spec IN SELECT * FROM pg_temp.tgsis_ms_spec s WHERE s.tab <> 'T' LOOP
        INSERT INTO pg_temp.tgsis_ms_key
        SELECT v_spec.tab, r[1]::float8, r[2]::bigint
          FROM tgsis.storage_run(v_spec.vt, false, format(
                 'SELECT DISTINCT ARRAY[v.%1$I::text, v.%2$I::text] FROM %3$I.%4$I v
                   WHERE v.%5$I = $1[1]::bigint AND v.%1$I = ANY ($1[2]::float8[])',
                 v_spec.tcol, v_spec.idcol, (v_spec.vt).schemaname, (v_spec.vt).tablename || '_ver', v_spec.okey),
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
        SELECT coalesce(string_agg(format('v.%I::text', a.attname), ', ' ORDER BY a.attnum), ''),
               coalesce(string_agg(CASE WHEN a.atttypid IN ('real'::regtype, 'double precision'::regtype)
                                        THEN format('coalesce((v.%I::float8 + 0::float8)::text, ''NaN'')', a.attname)
                                        ELSE format('coalesce(v.%I::text, ''NaN'')', a.attname) END, ', ' ORDER BY a.attnum), '')
          INTO v_vals, v_eq
          FROM pg_catalog.pg_attribute a
         WHERE a.attrelid = format('%I.%I', (v_spec.vt).schemaname, (v_spec.vt).tablename)::regclass
           AND a.attnum > 0 AND NOT a.attisdropped
           AND a.attname <> ALL (ARRAY[v_spec.okey, v_spec.tcol, coalesce(v_spec.idcol, v_spec.tcol)]);
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
                 (SELECT coalesce(string_agg(format('coalesce(v.%I::text, ''NaN'')', a.attname), ', ' ORDER BY a.attnum), '')
                    FROM pg_catalog.pg_attribute a
                   WHERE a.attrelid = format('%I.%I', (v_spec.vt).schemaname, (v_spec.vt).tablename)::regclass
                     AND a.attnum > 0 AND NOT a.attisdropped
                     AND a.attname <> ALL (ARRAY[v_spec.okey, v_spec.tcol, coalesce(v_spec.idcol, v_spec.tcol)])),
                 v_eq, CASE WHEN v_spec.tab = 'T' THEN '''''' ELSE v_el END,
                 (v_spec.vt).schemaname, (v_spec.vt).tablename || '_ver', v_spec.okey,
                 -- (the keys first: each found through the primary key, not by a scan of the instants' rows)
                 CASE WHEN v_spec.idcol IS NULL
                      THEN format('%I.%I v', (v_spec.vt).schemaname, (v_spec.vt).tablename || '_ver')
                      ELSE format('(SELECT DISTINCT k.t, k.id FROM unnest($1[4]::float8[], $5) AS k (t, id)) AS k
                                   JOIN %I.%I v ON v.%I = k.t AND v.%I = k.id',
                                  (v_spec.vt).schemaname, (v_spec.vt).tablename || '_ver', v_spec.tcol, v_spec.idcol) END),
               p_1 => ARRAY[v_key, v_spec.ts::text, v_cset::text, v_spec.kts::text], p_2 => v_base,
               p_3 => v_parent.workingset, p_5 => v_spec.ids) AS r;
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
        INSERT INTO pg_temp.tgsis_ms_pros
        SELECT r[1]::smallint AS st, r[2]::float8 AS t, r[3:] AS vals
          FROM tgsis.storage_run(v_pros, false, format(
                 'SELECT ARRAY[s.st::text, v._times::text] || ARRAY[%s]
                    FROM %I.%I v, (VALUES (1, $2), (2, $3), (4, $1[2]::integer[])) AS s (st, revs)
                   WHERE v._geoid = $1[1]::bigint AND v.revision = ANY (s.revs) AND NOT (v.revclosed AND v.lastrevs && s.revs)',
                 (SELECT string_agg(format('v.%I::text', c), ', ') FROM unnest(v_pcols) AS c),
                 v_pros.schemaname, v_pros.tablename || '_ver'),
               p_1 => ARRAY[v_key, v_cset::text], p_2 => v_base, p_3 => v_parent.workingset) AS r;
        FOR v_attr IN
            SELECT k.t, b.vals AS b, p.vals AS p, c.vals AS c
              FROM (SELECT DISTINCT x.t FROM pg_temp.tgsis_ms_pros x) AS k
              LEFT JOIN pg_temp.tgsis_ms_pros b ON b.st = 1 AND b.t = k.t
              LEFT JOIN pg_temp.tgsis_ms_pros p ON p.st = 2 AND p.t = k.t
              LEFT JOIN pg_temp.tgsis_ms_pros c ON c.st = 4 AND c.t = k.t
             ORDER BY k.t
        LOOP
            IF v_attr.p IS NOT DISTINCT FROM v_attr.c OR v_attr.c IS NOT DISTINCT FROM v_attr.b THEN
                INSERT INTO pg_temp.tgsis_ms_prow VALUES (v_attr.t, v_attr.p, v_attr.c);  -- the parent's row
            ELSIF v_attr.p IS NOT DISTINCT FROM v_attr.b THEN
                INSERT INTO pg_temp.tgsis_ms_prow VALUES (v_attr.t, v_attr.c, v_attr.c);  -- the version's row
            ELSIF v_attr.p IS NULL OR v_attr.c IS NULL OR v_attr.b IS NULL THEN
                RETURN NULL;  -- removed (added) on one side and set otherwise on the other: an object-level conflict
            ELSIF EXISTS (SELECT FROM generate_subscripts(v_attr.b, 1) AS i
                           WHERE v_attr.p[i] IS DISTINCT FROM v_attr.c[i] AND v_attr.c[i] IS DISTINCT FROM v_attr.b[i]
                             AND v_attr.p[i] IS DISTINCT FROM v_attr.b[i]) THEN
                RETURN NULL;  -- a column changed on both sides to other values: an object-level conflict
            ELSE  -- column by column: the side that changed it
                INSERT INTO pg_temp.tgsis_ms_prow
                VALUES (v_attr.t, ARRAY(SELECT CASE WHEN v_attr.c[i] IS NOT DISTINCT FROM v_attr.b[i] THEN v_attr.p[i]
                                                    ELSE v_attr.c[i] END
                                          FROM generate_subscripts(v_attr.b, 1) AS i ORDER BY i), v_attr.c);
            END IF;
        END LOOP;
    END IF;

    IF p_action = 'regions' THEN  -- the analysis only (tgsis.instants_merge_regions reads tgsis_ms_slice): no object-level conflict
        RETURN 0;
    END IF;

    -- the parent's edits of the attributes (geometry row, feature row), as tgsis.merge_mesh_by_region brings them
    FOR v_attr IN
        SELECT e.viewname, e.keycolumn,
               string_agg(format('%I = %L', e.columnname, e.value), ', ' ORDER BY e.o) AS sets,
               array_agg(e.columnname ORDER BY e.o) AS columns
          FROM (SELECT a.*, row_number() OVER () AS o
                  FROM tgsis.merge_attribute_edits(p_version, p_geoid, v_base, v_parent.workingset, v_cset) AS a) AS e
         GROUP BY e.viewname, e.keycolumn ORDER BY min(e.o)
    LOOP
        IF v_attr.viewname = 'tgsis.geometry' THEN
            v_aview := v_aview || v_attr.viewname;
            v_akey := v_akey || v_attr.keycolumn;
            v_aset := v_aset || v_attr.sets;
        ELSE
            v_fcols := v_attr.columns;
        END IF;
    END LOOP;

    -- the rights: to write in the version, to change the class (and the feature-row columns the parent changed)
    FOREACH v_why IN ARRAY v_notes LOOP  -- what the solutions discard, said before it is written
        RAISE NOTICE 'feature % of version %: %', p_geoid, quote_literal(p_version), v_why;
    END LOOP;
    PERFORM tgsis.merge_write_rights(p_version, p_geoid, v_fcols, 'instant by instant', 'surface');

    -- 7. the writes, in the version's working revision, as write_sliced_difference writes them: per table, the rows
    -- whose key is gone or whose bits differ closed, then the new and differing ones inserted
    v_settings := ARRAY[current_setting('tgsis.version', true), current_setting('tgsis.revision', true)];
    PERFORM tgsis.goto_version(p_version, true);
    SELECT workingrevision, workingset INTO v_rev, v_cset FROM tgsis.versions WHERE versionid = v_version.versionid;
    PERFORM tgsis.check_objects_unlocked(t.objectclass, ARRAY[v_key])
       FROM tgsis.versioned_tables t WHERE t.schemaname = 'tgsis' AND t.tablename = 'geometry';
    PERFORM tgsis.object_write_lock('feature', ARRAY[v_key]);
    -- the per-instant feature property rows first (as _write_instant_rows: a DELETE, INSERT or UPDATE of the
    -- class's view per instant, which its trigger writes: a row of the working revision in place, any other
    -- closed there and written anew)
    IF v_pcols IS NOT NULL THEN
        SELECT string_agg(format('%I', c), ', ' ORDER BY o),
               string_agg(format('$1[%s]::%s', o + 2, (SELECT format_type(a.atttypid, a.atttypmod) FROM pg_catalog.pg_attribute a
                                                       WHERE a.attrelid = format('%I.%I', v_pros.schemaname, v_pros.tablename)::regclass
                                                         AND a.attname = c)), ', ' ORDER BY o),
               string_agg(format('%I = $1[%s]::%s', c, o + 2, (SELECT format_type(a.atttypid, a.atttypmod) FROM pg_catalog.pg_attribute a
                                                               WHERE a.attrelid = format('%I.%I', v_pros.schemaname, v_pros.tablename)::regclass
                                                                 AND a.attname = c)), ', ' ORDER BY o)
          INTO v_cols, v_casts, v_why
          FROM unnest(v_pcols) WITH ORDINALITY AS u(c, o);
        FOR v_attr IN SELECT * FROM pg_temp.tgsis_ms_prow r WHERE r.m IS DISTINCT FROM r.c ORDER BY r.t LOOP
            PERFORM tgsis.check_merge_table_write(v_pros, CASE WHEN v_attr.c IS NULL THEN 'INSERT'
                                                              WHEN v_attr.m IS NULL THEN 'DELETE' ELSE 'UPDATE' END, p_geoid);
            v_count := 0;
            IF v_attr.m IS NOT NULL AND v_attr.c IS NOT NULL THEN  -- in place in the working revision
                SELECT r[1]::bigint INTO v_count FROM tgsis.storage_run(v_pros, true, format(
                    'UPDATE %I.%I v SET %s WHERE v._geoid = $1[1]::bigint AND v._times = $1[2]::float8
                        AND v.revision = $4 AND NOT (v.lastrevs && $2)',
                    v_pros.schemaname, v_pros.tablename || '_ver', v_why),
                    p_1 => ARRAY[v_key, v_attr.t::text] || v_attr.m, p_2 => v_cset, p_4 => v_rev) AS r;
            END IF;
            IF v_count = 0 AND v_attr.c IS NOT NULL THEN  -- the version's row goes (closed, or gone if its revision's)
                SELECT r[1]::bigint INTO v_count FROM tgsis.storage_run(v_pros, true, format(
                    'DELETE FROM %I.%I v WHERE v._geoid = $1[1]::bigint AND v._times = $1[2]::float8 AND v.revision = $4',
                    v_pros.schemaname, v_pros.tablename || '_ver'),
                    p_1 => ARRAY[v_key, v_attr.t::text], p_4 => v_rev) AS r;
                IF v_count = 0 THEN
                    SELECT r[1]::bigint INTO v_count FROM tgsis.storage_run(v_pros, true, format(
                        'UPDATE %I.%I v SET lastrevs = v.lastrevs || $4
                          WHERE v._geoid = $1[1]::bigint AND v._times = $1[2]::float8 AND v.revision = ANY ($2)
                            AND NOT (v.lastrevs && $2)',
                        v_pros.schemaname, v_pros.tablename || '_ver'),
                        p_1 => ARRAY[v_key, v_attr.t::text], p_2 => v_cset, p_4 => v_rev) AS r;
                    PERFORM tgsis.note_changed_objects(v_pros.schemaname, v_pros.tablename, v_rev, ARRAY[v_key]);
                END IF;
                IF v_attr.m IS NOT NULL THEN
                    v_count := 0;  -- (an UPDATE of the view: one row)
                END IF;
            END IF;
            IF v_attr.m IS NOT NULL AND v_count = 0 THEN
                SELECT r[1]::bigint INTO v_count FROM tgsis.storage_run(v_pros, true, format(
                    'INSERT INTO %I.%I (_geoid, _times, %s, revision) SELECT $1[1]::bigint, $1[2]::float8, %s, $4',
                    v_pros.schemaname, v_pros.tablename || '_ver', v_cols, v_casts),
                    p_1 => ARRAY[v_key, v_attr.t::text] || v_attr.m, p_4 => v_rev) AS r;
            END IF;
            v_written := v_written + v_count;
        END LOOP;
    END IF;
    FOR v_spec IN SELECT * FROM pg_temp.tgsis_ms_spec s
                   ORDER BY array_position(ARRAY['T', 'v', 'c', 'vp', 'cp'], s.tab) LOOP
        -- (old: the version's rows; new: the merged; a property row compared as the state holds it, NaN if none)
        IF v_spec.tab = 'T' THEN
            SELECT coalesce(array_agg(s.t ORDER BY s.t), '{}'), coalesce(array_agg(0::bigint), '{}') INTO v_times, v_ids
              FROM pg_temp.tgsis_ms_slice s
             WHERE s.ic AND NOT CASE s.src WHEN 'P' THEN s.ip WHEN 'C' THEN s.ic ELSE true END;
        ELSE
            SELECT coalesce(array_agg(o.t ORDER BY o.t, o.id), '{}'), coalesce(array_agg(o.id ORDER BY o.t, o.id), '{}')
              INTO v_times, v_ids
              FROM pg_temp.tgsis_ms_el o
             WHERE o.st = 4 AND o.kind = left(v_spec.tab, 1)
               AND NOT EXISTS (SELECT FROM pg_temp.tgsis_ms_new n
                                WHERE n.kind = o.kind AND n.t = o.t AND n.id = o.id
                                  AND CASE WHEN length(v_spec.tab) = 1 THEN n.gbits = o.gbits ELSE n.pbits = o.pbits END);
        END IF;
        IF cardinality(v_ids) > 0 THEN
            PERFORM tgsis.check_merge_table_write(v_spec.vt, 'DELETE', p_geoid);
            SELECT r[1]::bigint INTO v_count FROM tgsis.storage_run(v_spec.vt, true, format(
                'DELETE FROM %I.%I v USING (SELECT DISTINCT k.t, k.id FROM unnest($1[2]::float8[], $5) AS k (t, id)) AS k
                  WHERE v.%I = $1[1]::bigint AND v.revision = $4 AND v.%I = k.t AND %s = k.id',
                (v_spec.vt).schemaname, (v_spec.vt).tablename || '_ver', v_spec.okey, v_spec.tcol,
                CASE WHEN v_spec.idcol IS NULL THEN '0::bigint' ELSE format('v.%I', v_spec.idcol) END),
                p_1 => ARRAY[v_key, v_times::text], p_4 => v_rev, p_5 => v_ids) AS r;
            v_written := v_written + v_count;
            SELECT r[1]::bigint INTO v_count FROM tgsis.storage_run(v_spec.vt, true, format(
                'UPDATE %I.%I v SET lastrevs = v.lastrevs || $4
                   FROM (SELECT DISTINCT k.t, k.id FROM unnest($1[2]::float8[], $5) AS k (t, id)) AS k
                  WHERE v.%I = $1[1]::bigint AND v.revision = ANY ($3) AND NOT (v.lastrevs && $3)
                    AND v.%I = k.t AND %s = k.id',
                (v_spec.vt).schemaname, (v_spec.vt).tablename || '_ver', v_spec.okey, v_spec.tcol,
                CASE WHEN v_spec.idcol IS NULL THEN '0::bigint' ELSE format('v.%I', v_spec.idcol) END),
                p_1 => ARRAY[v_key, v_times::text], p_3 => v_cset, p_4 => v_rev, p_5 => v_ids) AS r;
            IF v_count > 0 THEN
                PERFORM tgsis.note_changed_objects((v_spec.vt).schemaname, (v_spec.vt).tablename, v_rev, ARRAY[v_key]);
            END IF;
            v_written := v_written + v_count;
        END IF;
        -- the rows to insert (a property row of no value is not written)
        IF v_spec.tab = 'T' THEN
            SELECT coalesce(array_agg(s.t ORDER BY s.t), '{}'), coalesce(array_agg(0::bigint), '{}'), '{}'
              INTO v_times, v_ids, v_flat
              FROM pg_temp.tgsis_ms_slice s
             WHERE NOT s.ic AND CASE s.src WHEN 'P' THEN s.ip WHEN 'C' THEN s.ic ELSE false END;
            v_width := 0;
        ELSE
            SELECT coalesce(array_agg(n.t ORDER BY n.t, n.id), '{}'), coalesce(array_agg(n.id ORDER BY n.t, n.id), '{}'),
                   coalesce(array_agg(u.v ORDER BY n.t, n.id, u.o), '{}')
              INTO v_times, v_ids, v_flat
              FROM pg_temp.tgsis_ms_new n
              LEFT JOIN LATERAL unnest(CASE WHEN length(v_spec.tab) = 1 THEN n.gvals ELSE n.pvals END)
                        WITH ORDINALITY AS u(v, o) ON true
             WHERE n.kind = left(v_spec.tab, 1)
               AND CASE WHEN length(v_spec.tab) = 1 THEN true ELSE n.pbits <> n.nulls END
               AND NOT EXISTS (SELECT FROM pg_temp.tgsis_ms_el o
                                WHERE o.st = 4 AND o.kind = n.kind AND o.t = n.t AND o.id = n.id
                                  AND CASE WHEN length(v_spec.tab) = 1 THEN n.gbits = o.gbits ELSE n.pbits = o.pbits END);
            -- (one id per element: the lateral unnest repeats it per value)
            SELECT coalesce(array_agg(n.t ORDER BY n.t, n.id), '{}'), coalesce(array_agg(n.id ORDER BY n.t, n.id), '{}')
              INTO v_times, v_ids
              FROM pg_temp.tgsis_ms_new n
             WHERE n.kind = left(v_spec.tab, 1)
               AND CASE WHEN length(v_spec.tab) = 1 THEN true ELSE n.pbits <> n.nulls END
               AND NOT EXISTS (SELECT FROM pg_temp.tgsis_ms_el o
                                WHERE o.st = 4 AND o.kind = n.kind AND o.t = n.t AND o.id = n.id
                                  AND CASE WHEN length(v_spec.tab) = 1 THEN n.gbits = o.gbits ELSE n.pbits = o.pbits END);
            v_width := CASE WHEN cardinality(v_ids) > 0 THEN cardinality(v_flat) / cardinality(v_ids) ELSE 0 END;
        END IF;
        CONTINUE WHEN cardinality(v_ids) = 0;
        PERFORM tgsis.check_merge_table_write(v_spec.vt, 'INSERT', p_geoid, true);  -- (the Python client COPYs them there)
        SELECT coalesce(string_agg(format(', %I', c.attname), '' ORDER BY c.attnum), ''),
               coalesce(string_agg(format(', $1[3 + (g.i - 1) * %s + %s]::%s', v_width, c.j,
                                          format_type(c.atttypid, c.atttypmod)), '' ORDER BY c.attnum), ''),
               string_agg(c.attname, ', ' ORDER BY c.attnum) FILTER (WHERE c.atttypid NOT IN ('real'::regtype, 'double precision'::regtype))
          INTO v_cols, v_casts, v_why
          FROM (SELECT a.attname, a.attnum, a.atttypid, a.atttypmod, row_number() OVER (ORDER BY a.attnum) AS j
                  FROM pg_catalog.pg_attribute a
                 WHERE a.attrelid = format('%I.%I', (v_spec.vt).schemaname, (v_spec.vt).tablename)::regclass
                   AND a.attnum > 0 AND NOT a.attisdropped
                   AND a.attname <> ALL (ARRAY[v_spec.okey, v_spec.tcol, coalesce(v_spec.idcol, v_spec.tcol)])) AS c;
        IF length(v_spec.tab) = 2 AND v_why IS NOT NULL AND EXISTS (SELECT FROM unnest(v_flat) AS f WHERE f IS NULL) THEN
            RAISE EXCEPTION '%: its merged rows cannot be written: some property rows have no value for an integer or boolean property',
                    v_refused
                USING ERRCODE = 'TG302', HINT = v_hint;
        END IF;
        SELECT r[1]::bigint INTO v_count FROM tgsis.storage_run(v_spec.vt, true, format(
            'INSERT INTO %I.%I (%I, %I%s%s, revision)
             SELECT $1[1]::bigint, ($1[2]::float8[])[g.i]%s%s, $4 FROM generate_series(1, cardinality($5)) AS g(i)',
            (v_spec.vt).schemaname, (v_spec.vt).tablename || '_ver', v_spec.okey, v_spec.tcol,
            CASE WHEN v_spec.idcol IS NULL THEN '' ELSE format(', %I', v_spec.idcol) END, v_cols,
            CASE WHEN v_spec.idcol IS NULL THEN '' ELSE ', $5[g.i]' END, v_casts),
            p_1 => ARRAY[v_key, v_times::text, ''] || v_flat, p_4 => v_rev, p_5 => v_ids) AS r;
        v_written := v_written + v_count;
    END LOOP;
    PERFORM FROM tgsis.refresh_geometry(p_geoid);
    v_written := v_written + tgsis.merge_apply_attribute_edits(p_geoid, v_aview, v_akey, v_aset, v_fcols,
                                                               v_parent.workingset, v_rev, v_cset);
    PERFORM set_config('tgsis.version', coalesce(v_settings[1], ''), true),
            set_config('tgsis.revision', coalesce(v_settings[2], ''), true);
    TRUNCATE pg_temp.tgsis_ms_spec, pg_temp.tgsis_ms_key, pg_temp.tgsis_ms_row, pg_temp.tgsis_ms_el,
             pg_temp.tgsis_ms_new, pg_temp.tgsis_ms_slice, pg_temp.tgsis_ms_pros, pg_temp.tgsis_ms_prow;
    PERFORM FROM tgsis.resolve_conflict(p_version, 'feature', v_key, 'manual');
    RETURN v_written;
END
$$;

REVOKE ALL ON FUNCTION tgsis.merge_instants_by_slice(text, text, bigint) FROM PUBLIC;

COMMENT ON FUNCTION tgsis.merge_instants_by_slice(text, text, bigint) IS
    'merge one model-2 feature (a surface at instants) changed both in a version and in its parent instant by instant, in SQL, exactly as the Python merge does: an instant one side added, removed or alone changed taken from it, one the version changed merged by region (merge3: tgsis.merge_instant_by_region, the parent/child/base/average/manual solutions of its conflicting regions), the merged instants written into the version by a difference keyed by (instant, id), the parent''s attribute edits brought in, the conflict recorded manual; NULL for an object-level conflict or an unsolved region (the merge refuses it), TG302 for what only the Python client merges (average or manual solutions recorded with their .npz only); p_action regions: the analysis only; returns the rows written';
