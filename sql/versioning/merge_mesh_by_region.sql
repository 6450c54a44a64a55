-- tgsis.merge_mesh_by_region(version, action, geoid): merge one model-1 feature by region in SQL, written into the version; returns the rows written.
-- The psql face of the Python merge by region (tgsis.db.merging._merge_object,
-- docs/merge.md), which is its oracle, row for row: the three states and the
-- regions are tgsis.mesh_merge_work's (the same as tgsis.merge3's); the merged
-- state is, per region, the rows of the side that changed it (a region both
-- changed alike: the parent's) or of the solution recorded for it
-- (tgsis.resolve_region: parent, child or base; average or manual: the rows
-- recorded with it, tgsis.merge_solution_rows), the parent's elsewhere, with
-- the version's new ids as merge3 renumbers them (tgsis_mr_vmap / _cmap). It is
-- written into the VERSION's working revision by an id-keyed difference
-- against the version's stored rows, as tgsis.db._state_write writes it: a
-- vertex or cell whose id is gone or whose row differs (coordinates bit for
-- bit, a cell's vertex ids in order) is closed (tgsis.delete_object_rows) and
-- a row whose id is new or differs is inserted with exactly the merged id; the
-- property rows alike (values equal as merge3 compares them; a row of no value
-- is not written), copied from the stored row of the state they come from; the
-- GOCAD atoms (tgsis.atom) alike, their refid renumbered with the vertices;
-- the part runs (tgsis.part) of the merged cells, rewritten when they differ
-- from the version's; the
-- geometry row's box and counts follow; the parent's edits of the feature's
-- attributes of the geometry row (name, colour, CRS, ...) are brought in, and
-- those of the feature row (tgsis.merge_feature_row: copied from the parent's
-- row through tgsis.storage_run, as the class's owner). Then the conflict
-- is recorded 'manual', and the merge or refresh that follows copies the
-- version's object as for any other solution. NULL, nothing written, when a
-- conflicting region has no solution (or the regions were not stored: none
-- could be recorded): the merge's refusal (TG302) names it.
-- Refused (TG302, nothing written: the caller's transaction is aborted) with the
-- hint naming the Python command that merges it: a region solved average or
-- manual recorded with its .npz only (no rows SQL reads), or whose rows SQL
-- does not apply (tgsis.merge_solution_rows says which), stored regions that are not the
-- regions of now, attributes changed on both sides, a merged mesh that is not
-- valid where no state was invalid (merge3's checks: cells on removed vertices,
-- duplicated cells, non-manifold edges or faces, vertices left without cells),
-- merged rows of no value for an integer property, a state with non-finite
-- coordinates (NaN, infinity; merge3 takes no such mesh). TG002 for a role that may
-- not write in the version, 42501 for one that may not change the class (or
-- the feature-row columns the parent changed). The work tables are made in a
-- subtransaction rolled back once the plan (the rows to close and to write) is
-- in variables: neither they nor their locks outlive the call.
-- extra_float_digits is pinned: values are compared as text, floats exactly.
-- It takes the merge's locks itself first (tgsis.lock_version_pair: parent,
-- then version, waiting for their writers; TG300 unless READ COMMITTED), as
-- tgsis.merge_regions_in_sql has before calling it: called alone, it still
-- reads the states after the writers it waited for and writes before any
-- other writer of either side.
CREATE FUNCTION tgsis.merge_mesh_by_region(p_version text, p_action text, p_geoid bigint)
RETURNS bigint
LANGUAGE plpgsql
VOLATILE
SET search_path = pg_catalog, pg_temp
SET extra_float_digits = 1
AS $$
DECLARE
    v_key      text := p_geoid::text;
    v_version  tgsis.versions;
    v_name     text := format('feature %s (base)', p_geoid);
    v_refused  text := format('%s of version %s refused: feature %s does not merge by region in SQL',
                              p_action, quote_literal(p_version), p_geoid);
    v_hint     text := format('`tgsis version %s %s` or tgsis.%s_version(conn, %s) in Python merges it by region '
                              '(average and manual solutions); else solve it as a whole object: '
                              'SELECT tgsis.resolve_conflict(%L, ''feature'', %L, ''parent''|''child''|''manual'')',
                              p_action, tgsis.shell_quote(p_version), p_action, pg_catalog.to_json(p_version)::text, p_version, p_geoid::text);
    v_why      text;
    v_word     text;
    v_table    text;
    v_cellid   text;
    v_k        integer;
    v_vps      text;
    v_vpn      text;
    v_cps      text;
    v_cpn      text;
    v_vnull    text;
    v_cnull    text;
    v_runs     boolean;
    -- the plan, computed in the subtransaction
    v_vgone    bigint[];
    v_vid      bigint[];
    v_vx       float8[];
    v_vy       float8[];
    v_vz       float8[];
    v_cgone    bigint[];
    v_cid      bigint[];
    v_cv       bigint[];
    v_pvgone   bigint[];
    v_pvid     bigint[];
    v_pvsrc    smallint[];
    v_pvfrom   bigint[];
    v_pcgone   bigint[];
    v_pcid     bigint[];
    v_pcsrc    smallint[];
    v_pcfrom   bigint[];
    v_agone    bigint[];
    v_pv8      text[] := '{}';
    v_pc8      text[] := '{}';
    v_parts    boolean := false;
    v_runs_old bigint[];
    v_touched  bigint[];
    v_same     boolean;
    v_runs_new bigint[];
    v_aid      bigint[];
    v_aref     bigint[];
    v_notes    text[];
    v_base     integer[];
    v_pset     integer[];
    v_cset     integer[];
    -- writing
    v_settings text[];
    v_rev      integer;
    v_count    bigint;
    v_written  bigint := 0;
    v_cols     text;
    v_vals     text;
    v_casts    text;
    v_width    integer;
    v_rowexpr  text;
    v_rows     text[];
    v_pt       tgsis.versioned_tables;
    v_t        record;
    v_note     text;
    v_aview    text[] := '{}';
    v_akey     text[] := '{}';
    v_aset     text[] := '{}';
    v_fcols    text[];
    v_unsolved boolean := false;
BEGIN
    -- the merge's locks, taken here whoever calls (tgsis.merge_regions_in_sql took them already: taken again, no
    -- wait): parent, then version, waiting for their writers (tgsis.lock_version_pair; TG300 unless READ
    -- COMMITTED), so that the three states read below are what those writers committed, and no writer of either
    -- side commits between the reads and the write (a write planned on a state a writer then changed would close
    -- the writer's row version: its edit lost)
    v_version := tgsis.lock_version_pair(p_version, p_action);

    -- the plan: the work tables in a subtransaction rolled back once the rows to write are in variables.
    -- The block's body is not indented.
    BEGIN
    PERFORM tgsis.mesh_merge_work(p_version, p_geoid);
    SELECT i.base, i.parentset, i.versionset, i.simplex, i.cellid, i.k, i.runs
      INTO v_base, v_pset, v_cset, v_table, v_cellid, v_k, v_runs
      FROM pg_temp.tgsis_mr_info i;
    v_word := CASE v_k WHEN 1 THEN 'point' WHEN 2 THEN 'segment' WHEN 3 THEN 'triangle' ELSE 'tetrahedron' END;
    -- a state with non-finite coordinates (NaN, infinity: a psql UPDATE stores them) is no mesh merge3 takes
    -- (MeshState): the Python merge refuses it; so does SQL, naming the first such state as Python does
    -- (base, parent, version), among the rows read: the changed ones and the base's around them
    IF pg_catalog.to_regclass('pg_temp.tgsis_mr_vb') IS NULL THEN  -- (not made when there is no region)
        CREATE TEMPORARY TABLE tgsis_mr_vb (id bigint, x float8, y float8, z float8) ON COMMIT DROP;
    END IF;
    SELECT format('feature %s (%s): vertices %s have non-finite coordinates', p_geoid,
                  CASE s.st WHEN 1 THEN 'base' WHEN 2 THEN 'parent' ELSE 'child' END,
                  tgsis.merge_ids_text(ARRAY(
                      SELECT m.id::text FROM (SELECT m.id, m.x, m.y, m.z FROM pg_temp.tgsis_mr_v m WHERE m.st = s.st
                                              UNION ALL SELECT b.id, b.x, b.y, b.z FROM pg_temp.tgsis_mr_vb b) AS m
                       WHERE 'NaN'::float8 IN (m.x, m.y, m.z) OR 'Infinity'::float8 IN (abs(m.x), abs(m.y), abs(m.z))
                       ORDER BY m.id)))
      INTO v_why
      FROM (VALUES (1::smallint), (2), (4)) AS s (st)
     WHERE EXISTS (SELECT FROM (SELECT m.x, m.y, m.z FROM pg_temp.tgsis_mr_v m WHERE m.st = s.st
                                UNION ALL SELECT b.x, b.y, b.z FROM pg_temp.tgsis_mr_vb b) AS m
                    WHERE 'NaN'::float8 IN (m.x, m.y, m.z) OR 'Infinity'::float8 IN (abs(m.x), abs(m.y), abs(m.z)))
     ORDER BY s.st LIMIT 1;
    IF v_why IS NOT NULL THEN
        RAISE EXCEPTION '%: %', v_refused, v_why
            USING ERRCODE = 'TG302', HINT = 'correct the coordinates in the version or its parent, or solve it as a whole object: '
                                            || format('SELECT tgsis.resolve_conflict(%L, ''feature'', %L, ''parent''|''child''|''manual'')',
                                                      p_version, p_geoid::text);
    END IF;

    -- parts kept as runs (tgsis.part) when some state has one: the runs are the object's, rewritten below when
    -- they differ (as the Python merge reads such an object whole)
    v_parts := v_runs AND EXISTS (SELECT FROM tgsis.part_ver v WHERE v.geoid = p_geoid
                                     AND ((v.revision = ANY (v_base) AND NOT (v.lastrevs && v_base))
                                          OR (v.revision = ANY (v_pset) AND NOT (v.lastrevs && v_pset))
                                          OR (v.revision = ANY (v_cset) AND NOT (v.lastrevs && v_cset))));

    -- the regions, their sources, the merged rows and what the solutions discard (pg_temp.tgsis_mw_*); unsolved
    -- (NULL) when a conflicting region has no solution or the regions are not stored yet
    IF tgsis.merge_region_plan(v_version.versionid, p_version, p_geoid, v_key, NULL, v_refused, v_hint) THEN
        v_unsolved := true;
        RAISE EXCEPTION 'tgsis_mw_done';
    END IF;
    v_notes := ARRAY(SELECT format('region %s: %s discards the %s''s edit there: %s vertices, %s cells, largest displacement %s',
                                   t.region, t.solution, t.side, t.nv, t.nc, tgsis.merge_number_text(t.d))
                       FROM pg_temp.tgsis_mw_notes t ORDER BY t.region, t.o);
    -- the version's rows as stored (its own numbering: the renumbering undone)
    CREATE TEMPORARY TABLE tgsis_mw_vold ON COMMIT DROP AS
    SELECT coalesce(p.old, m.id) AS id, m.x, m.y, m.z, m.val, coalesce(q.old, m.ref) AS ref
      FROM pg_temp.tgsis_mr_v m LEFT JOIN pg_temp.tgsis_mr_vmap p ON p.new = m.id
      LEFT JOIN pg_temp.tgsis_mr_vmap q ON q.new = m.ref
     WHERE m.st = 4;
    CREATE TEMPORARY TABLE tgsis_mw_cold ON COMMIT DROP AS
    SELECT coalesce(p.old, m.id) AS id,
           ARRAY(SELECT coalesce(q.old, u.x) FROM unnest(m.v) WITH ORDINALITY AS u(x, o)
                   LEFT JOIN pg_temp.tgsis_mr_vmap q ON q.new = u.x ORDER BY u.o) AS v, m.val
      FROM pg_temp.tgsis_mr_c m LEFT JOIN pg_temp.tgsis_mr_cmap p ON p.new = m.id
     WHERE m.st = 4;
    IF pg_catalog.to_regclass('pg_temp.tgsis_mw_sc') IS NOT NULL THEN  -- margin cells a solution rewrites: the base's
        INSERT INTO pg_temp.tgsis_mw_cold (id, v, val)
        SELECT s.id, s.bv, s.bval FROM pg_temp.tgsis_mw_sc s WHERE s.inside AND NOT s.changed AND s.based;
        -- and the region's vertices no state changed that a solution moves, revalues or removes: the base's
        INSERT INTO pg_temp.tgsis_mw_vold (id, x, y, z, val, ref)
        SELECT s.id, s.b_x, s.b_y, s.b_z, s.bval, s.bref FROM pg_temp.tgsis_mw_sv s WHERE s.inside AND NOT s.changed AND s.based;
    END IF;

    PERFORM tgsis.merge_mesh_validity(v_name, v_k, v_word, v_table, p_geoid, v_base, v_refused, v_hint);

    -- the difference, keyed by id: rows to close (gone, or differing) and rows to write (new, or differing)
    v_vgone := ARRAY(SELECT o.id FROM pg_temp.tgsis_mw_vold o
                      WHERE NOT EXISTS (SELECT FROM pg_temp.tgsis_mw_v n
                                         WHERE n.present AND n.id = o.id AND float8send(n.x) = float8send(o.x)
                                           AND float8send(n.y) = float8send(o.y) AND float8send(n.z) = float8send(o.z))
                      ORDER BY o.id);
    SELECT coalesce(array_agg(n.id ORDER BY n.id), '{}'), coalesce(array_agg(n.x ORDER BY n.id), '{}'),
           coalesce(array_agg(n.y ORDER BY n.id), '{}'), coalesce(array_agg(n.z ORDER BY n.id), '{}')
      INTO v_vid, v_vx, v_vy, v_vz
      FROM pg_temp.tgsis_mw_v n
     WHERE n.present
       AND NOT EXISTS (SELECT FROM pg_temp.tgsis_mw_vold o
                        WHERE o.id = n.id AND float8send(n.x) = float8send(o.x)
                          AND float8send(n.y) = float8send(o.y) AND float8send(n.z) = float8send(o.z));
    v_cgone := ARRAY(SELECT o.id FROM pg_temp.tgsis_mw_cold o
                      WHERE NOT EXISTS (SELECT FROM pg_temp.tgsis_mw_c n WHERE n.present AND n.id = o.id AND n.v = o.v)
                      ORDER BY o.id);
    SELECT coalesce(array_agg(n.id ORDER BY n.id), '{}'), coalesce(array_agg(u.x ORDER BY n.id, u.o), '{}')
      INTO v_cid, v_cv
      FROM pg_temp.tgsis_mw_c n CROSS JOIN LATERAL unnest(n.v) WITH ORDINALITY AS u(x, o)
     WHERE n.present AND NOT EXISTS (SELECT FROM pg_temp.tgsis_mw_cold o WHERE o.id = n.id AND o.v = n.v);
    v_cid := ARRAY(SELECT DISTINCT u FROM unnest(v_cid) AS u ORDER BY 1);
    -- the part runs of the version's cells now and of the merged cells (cells in no run stay in none; a run
    -- never spans a gap in the ids), over every cell: those no state changed have the base's part. The two
    -- states differ only at the ids of the work rows (the version's changed cells, the merged ones): when the
    -- cells of those ids have the same parts in both, so have the runs, and nothing is read beyond those ids
    -- (stored in chunks: the chunks holding them, not every cell of the version)
    IF v_parts THEN
        v_touched := ARRAY(SELECT coalesce(p.old, m.id) FROM pg_temp.tgsis_mr_c m LEFT JOIN pg_temp.tgsis_mr_cmap p ON p.new = m.id
                            WHERE m.st = 4
                           UNION SELECT n.id FROM pg_temp.tgsis_mw_c n
                           ORDER BY 1);
        EXECUTE format(
            'WITH kept AS (
                 SELECT c.%3$I AS id, r.part FROM %1$s c JOIN %2$s r
                     ON r.geoid = $1 AND r.revision = ANY ($2) AND NOT (r.lastrevs && $2) AND c.%3$I BETWEEN r.firstid AND r.lastid
                  WHERE c.geoid = $1 AND c.revision = ANY ($2) AND NOT (c.lastrevs && $2) AND c.%3$I = ANY ($3)
                    AND NOT EXISTS (SELECT FROM pg_temp.tgsis_mr_c m WHERE m.id = c.%3$I)),
             states AS (
                 SELECT 4 AS st, k.id, k.part FROM kept k
                 UNION ALL SELECT 4, coalesce(p.old, m.id), m.part
                             FROM pg_temp.tgsis_mr_c m LEFT JOIN pg_temp.tgsis_mr_cmap p ON p.new = m.id WHERE m.st = 4
                 UNION ALL SELECT 8, k.id, k.part FROM kept k
                            WHERE NOT EXISTS (SELECT FROM pg_temp.tgsis_mw_c n WHERE n.id = k.id)
                 UNION ALL SELECT 8, n.id, n.part FROM pg_temp.tgsis_mw_c n WHERE n.present)
             SELECT coalesce(array_agg(ARRAY[s.id, s.part] ORDER BY s.id, s.part) FILTER (WHERE s.st = 4), ''{}'')
                    IS NOT DISTINCT FROM
                    coalesce(array_agg(ARRAY[s.id, s.part] ORDER BY s.id, s.part) FILTER (WHERE s.st = 8), ''{}'')
               FROM states s WHERE s.part >= 0',
            tgsis.storage_row_versions('tgsis', v_table, v_touched), tgsis.storage_table('tgsis', 'part'), v_cellid)
          INTO v_same USING p_geoid, v_base, v_touched;
        v_parts := NOT v_same;
    END IF;
    IF v_parts THEN
        EXECUTE format(
            'WITH kept AS (
                 SELECT c.%3$I AS id, r.part FROM %1$s c JOIN %2$s r
                     ON r.geoid = $1 AND r.revision = ANY ($2) AND NOT (r.lastrevs && $2) AND c.%3$I BETWEEN r.firstid AND r.lastid
                  WHERE c.geoid = $1 AND c.revision = ANY ($2) AND NOT (c.lastrevs && $2)
                    AND NOT EXISTS (SELECT FROM pg_temp.tgsis_mr_c m WHERE m.id = c.%3$I)),
             states AS (
                 SELECT 4 AS st, k.id, k.part FROM kept k
                 UNION ALL SELECT 4, coalesce(p.old, m.id), m.part
                             FROM pg_temp.tgsis_mr_c m LEFT JOIN pg_temp.tgsis_mr_cmap p ON p.new = m.id WHERE m.st = 4
                 UNION ALL SELECT 8, k.id, k.part FROM kept k
                            WHERE NOT EXISTS (SELECT FROM pg_temp.tgsis_mw_c n WHERE n.id = k.id)
                 UNION ALL SELECT 8, n.id, n.part FROM pg_temp.tgsis_mw_c n WHERE n.present),
             breaks AS (
                 SELECT s.st, s.id, s.part,
                        CASE WHEN lag(s.id) OVER w = s.id - 1 AND lag(s.part) OVER w = s.part THEN 0 ELSE 1 END AS brk
                   FROM states s WHERE s.part >= 0
                 WINDOW w AS (PARTITION BY s.st ORDER BY s.id)),
             runs AS (
                 SELECT b.st, min(b.id) AS firstid, max(b.id) AS lastid, min(b.part) AS part
                   FROM (SELECT b.*, sum(b.brk) OVER (PARTITION BY b.st ORDER BY b.id) AS g FROM breaks b) AS b
                  GROUP BY b.st, b.g)
             SELECT coalesce(array_agg(ARRAY[r.firstid, r.lastid, r.part] ORDER BY r.firstid) FILTER (WHERE r.st = 4), ''{}''),
                    coalesce(array_agg(ARRAY[r.firstid, r.lastid, r.part] ORDER BY r.firstid) FILTER (WHERE r.st = 8), ''{}'')
               FROM runs r',
            tgsis.storage_row_versions('tgsis', v_table), tgsis.storage_table('tgsis', 'part'), v_cellid)
          INTO v_runs_old, v_runs_new USING p_geoid, v_base;
    END IF;
    -- GOCAD atoms (tgsis.atom: a vertex that repeats another, refid): gone, new, or repeating another vertex now
    v_agone := ARRAY(SELECT o.id FROM pg_temp.tgsis_mw_vold o
                      WHERE o.ref IS NOT NULL
                        AND NOT EXISTS (SELECT FROM pg_temp.tgsis_mw_v n WHERE n.present AND n.id = o.id AND n.ref = o.ref)
                      ORDER BY o.id);
    SELECT coalesce(array_agg(n.id ORDER BY n.id), '{}'), coalesce(array_agg(n.ref ORDER BY n.id), '{}')
      INTO v_aid, v_aref
      FROM pg_temp.tgsis_mw_v n
     WHERE n.present AND n.ref IS NOT NULL
       AND NOT EXISTS (SELECT FROM pg_temp.tgsis_mw_vold o WHERE o.id = n.id AND o.ref = n.ref);
    -- property rows: values equal as merge3 compares them (the canonical texts); a row of no value is not written
    SELECT (SELECT nulls FROM tgsis.merge_value_text(i.vpschema, i.vptable)),
           (SELECT nulls FROM tgsis.merge_value_text(i.cpschema, i.cptable))
      INTO v_vnull, v_cnull FROM pg_temp.tgsis_mr_info i;
    IF v_vnull IS NOT NULL THEN
        v_pvgone := ARRAY(SELECT o.id FROM pg_temp.tgsis_mw_vold o
                           WHERE NOT EXISTS (SELECT FROM pg_temp.tgsis_mw_v n WHERE n.present AND n.id = o.id AND n.val = o.val)
                           ORDER BY o.id);
        SELECT coalesce(array_agg(n.id ORDER BY n.id), '{}'), coalesce(array_agg(n.src ORDER BY n.id), '{}'),
               coalesce(array_agg(CASE WHEN n.src = 4 THEN coalesce(p.old, n.id) ELSE n.id END ORDER BY n.id), '{}')
          INTO v_pvid, v_pvsrc, v_pvfrom
          FROM pg_temp.tgsis_mw_v n LEFT JOIN pg_temp.tgsis_mr_vmap p ON p.new = n.id
         WHERE n.present AND n.src <> 8 AND n.val <> v_vnull
           AND NOT EXISTS (SELECT FROM pg_temp.tgsis_mw_vold o WHERE o.id = n.id AND o.val = n.val);
        IF pg_catalog.to_regclass('pg_temp.tgsis_mw_sv') IS NOT NULL THEN  -- (an average or manual solution)
            v_pv8 := ARRAY(SELECT ARRAY[n.id::text] || s.w FROM pg_temp.tgsis_mw_v n JOIN pg_temp.tgsis_mw_sv s ON s.id = n.id
                            WHERE n.present AND n.src = 8 AND n.val <> v_vnull
                              AND NOT EXISTS (SELECT FROM pg_temp.tgsis_mw_vold o WHERE o.id = n.id AND o.val = n.val)
                            ORDER BY n.id);
        END IF;
    END IF;
    IF v_cnull IS NOT NULL THEN
        v_pcgone := ARRAY(SELECT o.id FROM pg_temp.tgsis_mw_cold o
                           WHERE NOT EXISTS (SELECT FROM pg_temp.tgsis_mw_c n WHERE n.present AND n.id = o.id AND n.val = o.val)
                           ORDER BY o.id);
        SELECT coalesce(array_agg(n.id ORDER BY n.id), '{}'), coalesce(array_agg(n.src ORDER BY n.id), '{}'),
               coalesce(array_agg(CASE WHEN n.src = 4 THEN coalesce(p.old, n.id) ELSE n.id END ORDER BY n.id), '{}')
          INTO v_pcid, v_pcsrc, v_pcfrom
          FROM pg_temp.tgsis_mw_c n LEFT JOIN pg_temp.tgsis_mr_cmap p ON p.new = n.id
         WHERE n.present AND n.src <> 8 AND n.val <> v_cnull
           AND NOT EXISTS (SELECT FROM pg_temp.tgsis_mw_cold o WHERE o.id = n.id AND o.val = n.val);
        IF pg_catalog.to_regclass('pg_temp.tgsis_mw_sc') IS NOT NULL THEN  -- (an average or manual solution)
            v_pc8 := ARRAY(SELECT ARRAY[n.id::text] || s.w FROM pg_temp.tgsis_mw_c n JOIN pg_temp.tgsis_mw_sc s ON s.id = n.id
                            WHERE n.present AND n.src = 8 AND n.val <> v_cnull
                              AND NOT EXISTS (SELECT FROM pg_temp.tgsis_mw_cold o WHERE o.id = n.id AND o.val = n.val)
                            ORDER BY n.id);
        END IF;
    END IF;
    SELECT i.vpschema, i.vptable, i.cpschema, i.cptable INTO v_vps, v_vpn, v_cps, v_cpn FROM pg_temp.tgsis_mr_info i;
    RAISE EXCEPTION 'tgsis_mw_done';  -- rolls the work tables and their locks back
    EXCEPTION WHEN raise_exception THEN
        IF SQLERRM <> 'tgsis_mw_done' THEN
            RAISE;
        END IF;
    END;
    IF v_unsolved THEN
        RETURN NULL;
    END IF;

    -- the parent's edits of the attributes, and the refusal of attributes changed on both sides
    SELECT a.p_views, a.p_keys, a.p_sets, a.p_fcols, a.p_both INTO v_aview, v_akey, v_aset, v_fcols, v_why
      FROM tgsis.merge_attribute_writes(p_version, p_geoid, v_base, v_pset, v_cset) AS a;
    IF v_why IS NOT NULL THEN
        RAISE EXCEPTION '%: its attributes were changed both in the version and in its parent, to other values (%): the merge by region merges the mesh only',
                v_refused, v_why
            USING ERRCODE = 'TG302', HINT = v_hint;
    END IF;

    FOREACH v_note IN ARRAY v_notes LOOP
        RAISE NOTICE 'feature % of version %: %', p_geoid, quote_literal(p_version), v_note;
    END LOOP;

    -- the merged mesh goes into the version first: the right to write there, to change the class and the
    -- feature-row columns whose parent's edits come along
    PERFORM tgsis.merge_write_rights(p_version, p_geoid, v_fcols, 'by region', 'mesh');

    -- the writes, in the version's working revision, as tgsis.db._state_write writes them
    v_settings := ARRAY[current_setting('tgsis.version', true), current_setting('tgsis.revision', true)];
    PERFORM tgsis.goto_version(p_version, true);
    SELECT workingrevision INTO v_rev FROM tgsis.versions WHERE versionid = v_version.versionid;
    PERFORM tgsis.check_objects_unlocked(t.objectclass, ARRAY[v_key])
       FROM tgsis.versioned_tables t WHERE t.schemaname = 'tgsis' AND t.tablename = 'vrtx';
    FOR v_t IN SELECT * FROM (VALUES ('VERTEX', v_vps, v_vpn, v_pvgone, v_pvid, v_pvsrc, v_pvfrom, v_pv8),
                                     ('CELL', v_cps, v_cpn, v_pcgone, v_pcid, v_pcsrc, v_pcfrom, v_pc8))
                                AS t (alignment, schemaname, tablename, gone, ids, src, src_ids, given)
                WHERE t.gone IS NOT NULL LOOP
        -- (statements on the class's storage through tgsis.storage_run: as its owner, never as tgsis's)
        SELECT * INTO v_pt FROM tgsis.versioned_tables t WHERE t.schemaname = v_t.schemaname AND t.tablename = v_t.tablename;
        SELECT count(*) + 1 INTO v_width FROM pg_catalog.pg_attribute a
         WHERE a.attrelid = format('%I.%I', v_t.schemaname, v_t.tablename)::regclass
           AND a.attnum > 0 AND NOT a.attisdropped AND a.attname NOT IN ('_geoid', '_idx');
        SELECT string_agg(format('%I', c.attname), ', ' ORDER BY c.attnum),
               string_agg(CASE WHEN c.atttypid IN ('real'::regtype, 'double precision'::regtype)
                               THEN format('coalesce(s.%I, ''NaN'')::text', c.attname)
                               WHEN c.atttypid IN ('real[]'::regtype, 'double precision[]'::regtype)
                               THEN format('(SELECT array_agg(coalesce(e, ''NaN'') ORDER BY o) FROM unnest(s.%I) WITH ORDINALITY AS u(e, o))::text',
                                           c.attname)
                               ELSE format('s.%I::text', c.attname) END, ', ' ORDER BY c.attnum),
               string_agg(format('$1[2 + (g.i - 1) * %s + %s]::%s', v_width, c.j,
                                 format_type(c.atttypid, c.atttypmod)), ', ' ORDER BY c.attnum)
          INTO v_cols, v_vals, v_casts
          FROM (SELECT a.attname, a.attnum, a.atttypid, a.atttypmod, row_number() OVER (ORDER BY a.attnum) AS j
                  FROM pg_catalog.pg_attribute a
                 WHERE a.attrelid = format('%I.%I', v_t.schemaname, v_t.tablename)::regclass
                   AND a.attnum > 0 AND NOT a.attisdropped AND a.attname NOT IN ('_geoid', '_idx')) AS c;
        -- the rows to write, read (as text: exact) before anything of the version is closed (they may be its own)
        v_rows := ARRAY(
            SELECT r FROM tgsis.storage_run(v_pt, false, format(
                'SELECT ARRAY[f.id::text, %s]
                   FROM (SELECT $5[g.i] AS id, $5[c.n + g.i] AS sid, $5[2 * c.n + g.i] AS src
                           FROM (SELECT cardinality($5) / 3 AS n) AS c, generate_series(1, cardinality($5) / 3) AS g(i)) AS f
                   JOIN %s s ON s._geoid = $1[1]::bigint AND s._idx = f.sid
                    AND s.revision = ANY (CASE f.src WHEN 1 THEN $2 WHEN 2 THEN $3 ELSE $1[2]::integer[] END)
                    AND NOT (s.lastrevs && CASE f.src WHEN 1 THEN $2 WHEN 2 THEN $3 ELSE $1[2]::integer[] END)
                  ORDER BY f.id', v_vals, tgsis.storage_row_versions(v_pt.schemaname, v_pt.tablename, v_t.src_ids)),
                p_1 => ARRAY[p_geoid::text, v_cset::text], p_2 => v_base, p_3 => v_pset,
                p_5 => v_t.ids || v_t.src_ids || v_t.src::bigint[]) AS r)
                  || v_t.given;  -- the rows of average and manual solutions, their values as the solution gives them
        SELECT string_agg(v_rows[i][1], ', ' ORDER BY i) INTO v_why
          FROM generate_subscripts(v_rows, 1) AS i
         WHERE EXISTS (SELECT FROM generate_subscripts(v_rows, 2) AS j WHERE v_rows[i][j] IS NULL);
        IF v_why IS NOT NULL THEN  -- (a float's NULL is written NaN, as the Python client writes it)
            RAISE EXCEPTION '%: its merged rows cannot be written: % property rows of ids % have no value for an integer or boolean property',
                    v_refused, lower(v_t.alignment), v_why
                USING ERRCODE = 'TG302', HINT = v_hint;
        END IF;
        IF tgsis.stored_in_chunks(v_pt.schemaname, v_pt.tablename) THEN
            -- a property table stored in chunks (tgsis.store_class_in_chunks): the rows that go and the rows
            -- written in one call of the chunk layer's bulk writer (tgsis.write_property_rows, named at run
            -- time: a layer above this one), each touched chunk rewritten once in the working revision with
            -- the face's checks for the calling role (through the face, each row's INSERT and DELETE rewrote
            -- its chunk); the rows written counted as through the face (gone, then written)
            SELECT string_agg(CASE a.attname WHEN '_geoid' THEN '$1[1]::bigint'
                                             WHEN '_idx' THEN format('$1[2 + (g.i - 1) * %s]::bigint', v_width)
                                             ELSE format('$1[2 + (g.i - 1) * %s + %s]::%s', v_width,
                                                         (SELECT count(*) FROM pg_catalog.pg_attribute b
                                                           WHERE b.attrelid = a.attrelid AND b.attnum > 0 AND NOT b.attisdropped
                                                             AND b.attname NOT IN ('_geoid', '_idx') AND b.attnum <= a.attnum),
                                                         format_type(a.atttypid, a.atttypmod)) END,
                              ', ' ORDER BY a.attnum)
              INTO v_rowexpr
              FROM pg_catalog.pg_attribute a
             WHERE a.attrelid = format('%I.%I', v_t.schemaname, v_t.tablename)::regclass AND a.attnum > 0 AND NOT a.attisdropped;
            EXECUTE format('SELECT tgsis.%I($2, $1[1]::bigint, $3,
                                   coalesce((SELECT array_agg(ROW(%s)::%s ORDER BY g.i)
                                               FROM generate_series(1, (cardinality($1) - 1) / %s) AS g(i)), ''{}''))',
                           'write_property_rows', v_rowexpr, format('%I.%I', v_t.schemaname, v_t.tablename), v_width)
              USING ARRAY[p_geoid::text] || ARRAY(SELECT unnest(v_rows)), format('%I.%I', v_t.schemaname, v_t.tablename), v_t.gone;
            v_written := v_written + cardinality(v_t.gone) + coalesce(array_length(v_rows, 1), 0);
            CONTINUE;
        END IF;
        v_written := v_written + tgsis.delete_object_rows(v_t.schemaname, v_t.tablename, '_geoid', ARRAY[p_geoid], '_idx', v_t.gone);
        IF cardinality(v_rows) > 0 THEN
            SELECT r[1]::bigint INTO v_count FROM tgsis.storage_run(v_pt, true, format(
                'INSERT INTO %I.%I (_geoid, _idx, %s, revision)
                 SELECT $1[1]::bigint, $1[2 + (g.i - 1) * %s]::bigint, %s, $4
                   FROM generate_series(1, (cardinality($1) - 1) / %s) AS g(i)',
                v_pt.schemaname, v_pt.tablename || '_ver', v_cols, v_width, v_casts, v_width),
                p_1 => ARRAY[p_geoid::text] || ARRAY(SELECT unnest(v_rows)), p_4 => v_rev) AS r;
            v_written := v_written + v_count;
        END IF;
    END LOOP;
    -- the vertices, then the cells: closed (gone or differing) and written (new or differing). Stored in chunks
    -- (issue 40, tgsis.stored_in_chunks): the touched chunks rewritten whole by the one chunk writer from a
    -- temporary table of the rows (a removed id becomes a hole), after the object's write lock, and the object
    -- noted as the face's triggers note it (no statement trigger on a chunk table does). The writer is in the
    -- chunks layer, above this one: named at run time (tests/test_sql_layers.py)
    FOR v_t IN SELECT * FROM (VALUES (1, 'vrtx', 'vrtxid'), (2, v_table, v_cellid)) AS t (o, tablename, idcol)
                WHERE tgsis.stored_in_chunks(t.tablename) ORDER BY t.o LOOP
        PERFORM tgsis.object_write_lock(t.objectclass, ARRAY[v_key])
           FROM tgsis.versioned_tables t WHERE t.schemaname = 'tgsis' AND t.tablename = v_t.tablename;
        DROP TABLE IF EXISTS pg_temp.tgsis_mw_rows;
        EXECUTE format('CREATE TEMPORARY TABLE tgsis_mw_rows ON COMMIT DROP AS
                        SELECT s.*, false AS _delete FROM tgsis.%I s WITH NO DATA', v_t.tablename || '_shape');
        IF v_t.o = 1 THEN
            INSERT INTO pg_temp.tgsis_mw_rows (geoid, vrtxid, x, y, z, _delete)
            SELECT p_geoid, u.id, u.x, u.y, u.z, false FROM unnest(v_vid, v_vx, v_vy, v_vz) AS u (id, x, y, z)
            UNION ALL
            SELECT p_geoid, g.id, NULL, NULL, NULL, true FROM unnest(v_vgone) AS g (id) WHERE NOT (g.id = ANY (v_vid));
            v_count := cardinality(v_vgone) + cardinality(v_vid);
        ELSE
            EXECUTE format('INSERT INTO pg_temp.tgsis_mw_rows (geoid, %I, %s, _delete)
                            SELECT $1, u.id, %s, false FROM unnest($2) WITH ORDINALITY AS u (id, o)
                            UNION ALL
                            SELECT $1, g.id, %s, true FROM unnest($4) AS g (id) WHERE NOT (g.id = ANY ($2))',
                           v_cellid,
                           (SELECT string_agg(format('vrtxid%s', i), ', ' ORDER BY i) FROM generate_series(1, v_k) AS i),
                           (SELECT string_agg(format('$3[(u.o - 1) * %s + %s]', v_k, i), ', ' ORDER BY i)
                              FROM generate_series(1, v_k) AS i),
                           (SELECT string_agg('NULL', ', ') FROM generate_series(1, v_k) AS i))
              USING p_geoid, v_cid, v_cv, v_cgone;
            v_count := cardinality(v_cgone) + cardinality(v_cid);
        END IF;
        IF v_count > 0 THEN
            EXECUTE format('SELECT tgsis.%I($1, $2)', 'write_chunk_rows') USING v_t.tablename, 'pg_temp.tgsis_mw_rows'::regclass;
            PERFORM tgsis.record_changed_objects('tgsis', v_t.tablename, ARRAY[v_key]);
            v_written := v_written + v_count;
        END IF;
    END LOOP;
    IF NOT tgsis.stored_in_chunks(v_table) THEN
        v_written := v_written + tgsis.delete_object_rows('tgsis', v_table, 'geoid', ARRAY[p_geoid], v_cellid, v_cgone);
    END IF;
    IF NOT tgsis.stored_in_chunks('vrtx') THEN
        v_written := v_written + tgsis.delete_object_rows('tgsis', 'vrtx', 'geoid', ARRAY[p_geoid], 'vrtxid', v_vgone);
        IF cardinality(v_vid) > 0 THEN
            EXECUTE format('INSERT INTO %s (geoid, vrtxid, x, y, z, revision) SELECT $1, u.id, u.x, u.y, u.z, $6
                              FROM unnest($2, $3, $4, $5) AS u (id, x, y, z)', tgsis.storage_table('tgsis', 'vrtx'))
              USING p_geoid, v_vid, v_vx, v_vy, v_vz, v_rev;
            v_written := v_written + cardinality(v_vid);
        END IF;
    END IF;
    IF NOT tgsis.stored_in_chunks(v_table) AND cardinality(v_cid) > 0 THEN
        EXECUTE format('INSERT INTO %s (geoid, %I, %s, revision) SELECT $1, u.id, %s, $4
                          FROM unnest($2) WITH ORDINALITY AS u (id, o)',
                       tgsis.storage_table('tgsis', v_table), v_cellid,
                       (SELECT string_agg(format('vrtxid%s', i), ', ' ORDER BY i) FROM generate_series(1, v_k) AS i),
                       (SELECT string_agg(format('$3[(u.o - 1) * %s + %s]', v_k, i), ', ' ORDER BY i)
                          FROM generate_series(1, v_k) AS i))
          USING p_geoid, v_cid, v_cv, v_rev;
        v_written := v_written + cardinality(v_cid);
    END IF;
    -- the atoms: closed, then written; a row that comes back as stored in some revision of the object takes its
    -- PATOM flag from there, any other is an ATOM (as tgsis.db._state_write writes them)
    v_written := v_written + tgsis.delete_object_rows('tgsis', 'atom', 'geoid', ARRAY[p_geoid], 'vrtxid', v_agone);
    IF cardinality(v_aid) > 0 THEN
        EXECUTE format('INSERT INTO %1$s (geoid, vrtxid, refid, patom, revision)
                        SELECT $1, u.id, u.ref,
                               coalesce((SELECT bool_or(a.patom) FROM %1$s a
                                          WHERE a.geoid = $1 AND a.vrtxid = u.id AND a.refid = u.ref), false), $4
                          FROM unnest($2, $3) AS u (id, ref)', tgsis.storage_table('tgsis', 'atom'))
          USING p_geoid, v_aid, v_aref, v_rev;
        v_written := v_written + cardinality(v_aid);
    END IF;
    -- the part runs, rewritten when they differ (a few rows per object)
    IF v_parts AND v_runs_old IS DISTINCT FROM v_runs_new THEN
        v_written := v_written + tgsis.delete_object_rows('tgsis', 'part', 'geoid', ARRAY[p_geoid]);
        IF cardinality(v_runs_new) > 0 THEN
            EXECUTE format('INSERT INTO %s (geoid, firstid, lastid, part, revision)
                            SELECT $1, $2[i][1], $2[i][2], $2[i][3]::integer, $3 FROM generate_subscripts($2, 1) AS i',
                           tgsis.storage_table('tgsis', 'part'))
              USING p_geoid, v_runs_new, v_rev;
            v_written := v_written + array_length(v_runs_new, 1);
        END IF;
    END IF;
    v_written := v_written + tgsis.merge_geometry_row(p_geoid, v_table,
                                                      (SELECT workingset FROM tgsis.versions WHERE versionid = v_version.versionid));
    v_written := v_written + tgsis.merge_apply_attribute_edits(
        p_geoid, v_aview, v_akey, v_aset, v_fcols, v_pset, v_rev,
        (SELECT workingset FROM tgsis.versions WHERE versionid = v_version.versionid));
    PERFORM set_config('tgsis.version', coalesce(v_settings[1], ''), true),
            set_config('tgsis.revision', coalesce(v_settings[2], ''), true);
    PERFORM FROM tgsis.resolve_conflict(p_version, 'feature', v_key, 'manual');
    RETURN v_written;
END
$$;

COMMENT ON FUNCTION tgsis.merge_mesh_by_region(text, text, bigint) IS
    'merge one model-1 feature changed both in a version and in its parent by region, in SQL, exactly as the Python merge by region does: the merged mesh (regions one side changed from that side, conflicting ones from their recorded parent/child/base solution or the rows recorded with an average/manual one) written into the version by id-keyed difference, the parent''s attribute edits (geometry and feature rows) brought in, the conflict recorded manual; NULL (nothing written) while a conflicting region has no solution; TG302 for what SQL does not merge (average/manual solutions with their .npz only, an invalid merged mesh), TG002 / 42501 without the right to write in the version / to change the class; returns the rows written';

-- internal to the merges: reached only through the SECURITY DEFINER merge, refresh, find_conflicts and
-- resolve functions, as their owner; not executable by PUBLIC (tests/test_function_grants.py)
REVOKE ALL ON FUNCTION tgsis.merge_mesh_by_region(text, text, bigint) FROM PUBLIC;
