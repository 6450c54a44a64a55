-- tgsis.merge_solution_rows(geoid, versionid, refused, hint): the rows the average and manual solutions give a feature merged b_y region in SQL.
-- For tgsis.merge_mesh_by_region, in its work tables (tgsis.mesh_merge_work's
-- pg_temp.tgsis_mr_*, its tgsis_mw_region with src 8 for a region solved
-- average or manual whose rows were recorded: tgsis.conflict_regions.solution_*,
-- kept b_y tgsis.resolve_region beside the .npz). As tgsis.merge3.apply_solutions
-- takes a manual state: its rows of the region's ids and of ids no state has
-- are the region's (pg_temp.tgsis_mw_sv, tgsis_mw_sc: coordinates or vertex
-- ids, the canonical text of the values as tgsis.merge_value_text makes it,
-- the texts to write, the atom's refid, the cell's part); a region id it
-- lacks is removed; its other rows must be the merged state's, else it is
-- refused (TG302; the Python merge refuses it TG100). Values come as float8 (the
-- Python client's arrays): a float column is written as the float8 (real: as
-- numpy rounds it to float4), an integer one truncated, as the Python writer
-- writes them; a value a column cannot hold (an integer one: infinite, beyond
-- its type; a real one: overflowing or underflowing float4) is refused (TG302),
-- as the Python writer refuses it; so are rows that are not the .npz's mesh
-- (tgsis.npz_rows_differ: the Python merge applies the .npz), a cell on one
-- vertex twice, an atom's refid or a cell's part that is no whole number. The
-- region's rows no state changed (the corners of cells a side removed, the
-- one-ring margin cells) are the solution's too, as in Python: a row that
-- differs from the base's is rewritten, one the solution lacks removed (the
-- base's rows read here for tgsis.merge_mesh_by_region to close). Refused too
-- (TG302, p_hint: the Python merge applies it): a class property column the
-- rows lack or of a type other than float, real or integer. An instant of a
-- surface at instants (tgsis_mr_info.times, tgsis.merge_instant_by_region):
-- the base's rows are that instant's (times_vrtx / times_trgl, property rows
-- keyed (_times, _idx)); no atoms. A geometry instant of a model-3 period
-- (tgsis_mr_info.timem too): the period's nodes at that geometry instant
-- (d4dvrtx), the period's triangles (d4dtrgl), property rows keyed (_timem,
-- _timet, _idx); the ids are node and triangle ids.
CREATE FUNCTION tgsis.merge_solution_rows(p_geoid bigint, p_versionid integer, p_refused text, p_hint text)
RETURNS void
LANGUAGE plpgsql
VOLATILE
SET search_path = pg_catalog, pg_temp
SET extra_float_digits = 1
AS $$
DECLARE
    v_key   text := p_geoid::text;
    v_info  record;
    v_side  record;
    v_canon text;
    v_write text;
    v_why   text;
BEGIN
    SELECT * INTO v_info FROM pg_temp.tgsis_mr_info;
    CREATE TEMPORARY TABLE tgsis_mw_sv ON COMMIT DROP AS
    SELECT g.region, u.id, r.solution_vertices[3 * u.o - 2] AS x, r.solution_vertices[3 * u.o - 1] AS y,
           r.solution_vertices[3 * u.o] AS z, r.solution_vertex_columns AS cols,
           r.solution_vertex_values[(u.o - 1) * cardinality(r.solution_vertex_columns) + 1
                                    : u.o * cardinality(r.solution_vertex_columns)] AS vals,
           NULL::text AS val, NULL::text[] AS w, NULL::bigint AS ref, NULL::bigint[] AS v, NULL::bigint AS part,
           u.id = ANY (g.vertex_ids) AS inside, EXISTS (SELECT FROM pg_temp.tgsis_mr_v m WHERE m.id = u.id) AS changed,
           false AS based, NULL::float8 AS b_x, NULL::float8 AS b_y, NULL::float8 AS b_z, NULL::bigint[] AS bv,
           NULL::text AS bval, NULL::bigint AS bpart, NULL::bigint AS bref, false AS gone
      FROM pg_temp.tgsis_mw_region g
      JOIN tgsis.conflict_regions r ON r.versionid = p_versionid AND r.objectclass = 'feature' AND r.objectkey = v_key
                                   AND r.region = g.region
     CROSS JOIN LATERAL unnest(r.solution_vertex_ids) WITH ORDINALITY AS u(id, o)
     WHERE g.conflict AND g.src = 8;
    CREATE TEMPORARY TABLE tgsis_mw_sc ON COMMIT DROP AS
    SELECT g.region, u.id, NULL::float8 AS x, NULL::float8 AS y, NULL::float8 AS z, r.solution_cell_columns AS cols,
           r.solution_cell_values[(u.o - 1) * cardinality(r.solution_cell_columns) + 1
                                  : u.o * cardinality(r.solution_cell_columns)] AS vals,
           NULL::text AS val, NULL::text[] AS w, NULL::bigint AS ref,
           r.solution_cells[(u.o - 1) * v_info.k + 1 : u.o * v_info.k] AS v, NULL::bigint AS part,
           u.id = ANY (g.cell_ids) AS inside, EXISTS (SELECT FROM pg_temp.tgsis_mr_c m WHERE m.id = u.id) AS changed,
           false AS based, NULL::float8 AS b_x, NULL::float8 AS b_y, NULL::float8 AS b_z, NULL::bigint[] AS bv,
           NULL::text AS bval, NULL::bigint AS bpart, false AS gone
      FROM pg_temp.tgsis_mw_region g
      JOIN tgsis.conflict_regions r ON r.versionid = p_versionid AND r.objectclass = 'feature' AND r.objectkey = v_key
                                   AND r.region = g.region
     CROSS JOIN LATERAL unnest(r.solution_cell_ids) WITH ORDINALITY AS u(id, o)
     WHERE g.conflict AND g.src = 8;

    -- rows that cannot be a mesh state's: cells of another size, an id given twice in one region
    SELECT format('region %s: %s', r.region,
                  CASE WHEN cardinality(r.solution_cells) <> v_info.k * cardinality(r.solution_cell_ids)
                       THEN format('%s cell vertex ids for %s cells of %s', cardinality(r.solution_cells),
                                   cardinality(r.solution_cell_ids), v_info.k)
                       ELSE 'an id is given twice' END)
      INTO v_why
      FROM tgsis.conflict_regions r JOIN pg_temp.tgsis_mw_region g ON g.region = r.region AND g.conflict AND g.src = 8
     WHERE r.versionid = p_versionid AND r.objectclass = 'feature' AND r.objectkey = v_key
       AND (cardinality(r.solution_cells) <> v_info.k * cardinality(r.solution_cell_ids)
            OR cardinality(r.solution_vertex_ids) <> (SELECT count(DISTINCT u) FROM unnest(r.solution_vertex_ids) AS u)
            OR cardinality(r.solution_cell_ids) <> (SELECT count(DISTINCT u) FROM unnest(r.solution_cell_ids) AS u))
     ORDER BY r.region LIMIT 1;
    IF v_why IS NULL THEN  -- the rows are the .npz's mesh (stored before resolve_region compared them: the Python merge
        -- would apply the .npz, so neither merges two copies that differ)
        SELECT string_agg(format('region %s: %s', r.region, d.why), '; ' ORDER BY r.region) INTO v_why
          FROM tgsis.conflict_regions r JOIN pg_temp.tgsis_mw_region g ON g.region = r.region AND g.conflict AND g.src = 8
         CROSS JOIN LATERAL (SELECT tgsis.npz_rows_differ(r.solution_mesh, r.solution_vertex_ids, r.solution_vertices,
                                                           r.solution_cell_ids, r.solution_cells, r.solution_vertex_columns,
                                                           r.solution_vertex_values, r.solution_cell_columns,
                                                           r.solution_cell_values) AS why) AS d
         WHERE r.versionid = p_versionid AND r.objectclass = 'feature' AND r.objectkey = v_key AND d.why IS NOT NULL;
        IF v_why IS NOT NULL THEN
            RAISE EXCEPTION '%: the recorded rows of its solution are not those of its .npz (%)', p_refused, v_why
                USING ERRCODE = 'TG302',
                      HINT = 'record the solution again, both from one mesh (tgsis.resolve_region), or solve the object as a whole (tgsis.resolve_conflict)';
        END IF;
    END IF;
    IF v_why IS NULL THEN  -- a cell on one vertex twice (no MeshState holds it; the storage's check would fail raw)
        SELECT string_agg(format('region %s: cells %s use a vertex twice', q.region, tgsis.merge_ids_text(q.ids)), '; '
                          ORDER BY q.region)
          INTO v_why
          FROM (SELECT s.region, array_agg(s.id::text ORDER BY s.id) AS ids FROM pg_temp.tgsis_mw_sc s
                 WHERE cardinality(s.v) > (SELECT count(DISTINCT x) FROM unnest(s.v) AS x)
                 GROUP BY s.region) AS q;
    END IF;
    IF v_why IS NOT NULL THEN
        RAISE EXCEPTION '%: the recorded rows of its solution are no mesh: %', p_refused, v_why
            USING ERRCODE = 'TG302', HINT = p_hint;
    END IF;

    -- the region's vertices and margin cells no state changed that the solution lacks: removed (their base rows read
    -- below), as merge3 removes a region row a manual state lacks
    INSERT INTO pg_temp.tgsis_mw_sv (region, id, cols, vals, inside, changed, based, gone)
    SELECT n.region, n.id, r.solution_vertex_columns, '{}', true, false, false, true
      FROM pg_temp.tgsis_mw_node n JOIN pg_temp.tgsis_mw_region g ON g.region = n.region AND g.conflict AND g.src = 8
      JOIN tgsis.conflict_regions r ON r.versionid = p_versionid AND r.objectclass = 'feature' AND r.objectkey = v_key
                                   AND r.region = g.region
     WHERE n.kind = 'v' AND NOT EXISTS (SELECT FROM pg_temp.tgsis_mr_v m WHERE m.id = n.id)
       AND NOT EXISTS (SELECT FROM pg_temp.tgsis_mw_sv s WHERE s.id = n.id AND s.region = n.region);
    INSERT INTO pg_temp.tgsis_mw_sc (region, id, cols, vals, inside, changed, based, gone)
    SELECT n.region, n.id, r.solution_cell_columns, '{}', true, false, false, true
      FROM pg_temp.tgsis_mw_node n JOIN pg_temp.tgsis_mw_region g ON g.region = n.region AND g.conflict AND g.src = 8
      JOIN tgsis.conflict_regions r ON r.versionid = p_versionid AND r.objectclass = 'feature' AND r.objectkey = v_key
                                   AND r.region = g.region
     WHERE n.kind = 'c' AND NOT EXISTS (SELECT FROM pg_temp.tgsis_mr_c m WHERE m.id = n.id)
       AND NOT EXISTS (SELECT FROM pg_temp.tgsis_mw_sc s WHERE s.id = n.id AND s.region = n.region);
    -- the base's rows of the ids no state changed (the region's margin, the rest around it)
    -- (an instant of a surface at instants, v_info.times: its rows of times_vrtx / times_trgl, no atoms; a geometry
    -- instant of a model-3 period, v_info.timem too: the period's nodes there, d4dvrtx, and its triangles, d4dtrgl)
    EXECUTE format('UPDATE pg_temp.tgsis_mw_sv s SET based = true, b_x = v.x, b_y = v.y, b_z = v.z FROM %s v
                     WHERE v.geoid = $1 AND v.%s = s.id AND NOT s.changed%s
                       AND v.revision = ANY ($2) AND NOT (v.revclosed AND v.lastrevs && $2)',
                   -- (stored in chunks: only the chunks of those ids decoded)
                   tgsis.storage_row_versions('tgsis', CASE WHEN v_info.times IS NULL THEN 'vrtx'
                                                            WHEN v_info.timem IS NULL THEN 'times_vrtx' ELSE 'd4dvrtx' END,
                                              ARRAY(SELECT s.id FROM pg_temp.tgsis_mw_sv s WHERE NOT s.changed)),
                   CASE WHEN v_info.timem IS NULL THEN 'vrtxid' ELSE 'nodeid' END,
                   CASE WHEN v_info.timem IS NOT NULL THEN ' AND v.timem = $4 AND v.timet = $3'
                        WHEN v_info.times IS NOT NULL THEN ' AND v.times = $3' ELSE '' END)
      USING p_geoid, v_info.base, v_info.times, v_info.timem;
    IF v_info.times IS NULL THEN
        EXECUTE format('UPDATE pg_temp.tgsis_mw_sv s SET bref = a.refid FROM %s a
                         WHERE s.based AND a.geoid = $1 AND a.vrtxid = s.id
                           AND a.revision = ANY ($2) AND NOT (a.revclosed AND a.lastrevs && $2)',
                       tgsis.storage_table('tgsis', 'atom'))
          USING p_geoid, v_info.base;
    END IF;
    EXECUTE format('UPDATE pg_temp.tgsis_mw_sc s SET based = true, bv = ARRAY[%s] FROM %s v
                     WHERE v.geoid = $1 AND v.%I = s.id AND NOT s.changed%s
                       AND v.revision = ANY ($2) AND NOT (v.revclosed AND v.lastrevs && $2)',
                   (SELECT string_agg(format('v.%s%s', CASE WHEN v_info.timem IS NULL THEN 'vrtxid' ELSE 'nodeid' END, i),
                                      ', ' ORDER BY i)
                      FROM generate_series(1, v_info.k) AS i),
                   tgsis.storage_row_versions('tgsis', v_info.simplex,
                                              ARRAY(SELECT s.id FROM pg_temp.tgsis_mw_sc s WHERE NOT s.changed)),
                   v_info.cellid,
                   CASE WHEN v_info.timem IS NOT NULL THEN ' AND v.timem = $4'
                        WHEN v_info.times IS NOT NULL THEN ' AND v.times = $3' ELSE '' END)
      USING p_geoid, v_info.base, v_info.times, v_info.timem;
    IF v_info.runs THEN  -- the base's part of those cells (tgsis.part's runs)
        EXECUTE format('UPDATE pg_temp.tgsis_mw_sc s SET bpart = r.part FROM %s r
                         WHERE s.based AND r.geoid = $1 AND s.id BETWEEN r.firstid AND r.lastid
                           AND r.revision = ANY ($2) AND NOT (r.revclosed AND r.lastrevs && $2)',
                       tgsis.storage_table('tgsis', 'part'))
          USING p_geoid, v_info.base;
    END IF;

    -- the values: canonical texts (as tgsis.merge_value_text) and the texts to write, from the float8 values
    FOR v_side IN SELECT * FROM (VALUES ('vertex', 'tgsis_mw_sv', v_info.vpschema, v_info.vptable),
                                        ('cell', 'tgsis_mw_sc', v_info.cpschema, v_info.cptable)) AS t (word, work, s, t) LOOP
        IF v_side.t IS NOT NULL AND (SELECT canon FROM tgsis.merge_value_text(v_side.s, v_side.t)) IS NOT NULL THEN
            SELECT string_agg(format('%s %s', quote_ident(a.attname), format_type(a.atttypid, a.atttypmod)), ', ' ORDER BY a.attnum)
              INTO v_why
              FROM pg_catalog.pg_attribute a
             WHERE a.attrelid = format('%I.%I', v_side.s, v_side.t)::regclass AND a.attnum > 0 AND NOT a.attisdropped
               AND a.attname NOT IN ('_geoid', '_times', '_timem', '_timet', '_idx')
               AND a.atttypid NOT IN ('real'::regtype, 'double precision'::regtype, 'smallint'::regtype,
                                      'integer'::regtype, 'bigint'::regtype);
            IF v_why IS NULL THEN
                EXECUTE format('SELECT string_agg(DISTINCT format(''region %%s lacks %%s'', s.region, c.c), ''; '')
                                  FROM pg_temp.%I s, unnest($1) AS c(c) WHERE NOT (c.c = ANY (s.cols))', v_side.work)
                   INTO v_why
                  USING ARRAY(SELECT a.attname::text FROM pg_catalog.pg_attribute a
                               WHERE a.attrelid = format('%I.%I', v_side.s, v_side.t)::regclass AND a.attnum > 0
                                 AND NOT a.attisdropped AND a.attname NOT IN ('_geoid', '_times', '_timem', '_timet', '_idx'));
            END IF;
            IF v_why IS NOT NULL THEN
                RAISE EXCEPTION '%: the % property columns of its solution rows are not the class''s (%)', p_refused, v_side.word, v_why
                    USING ERRCODE = 'TG302', HINT = p_hint;
            END IF;
            -- a value the column cannot hold, refused as the Python writer refuses it (not a raw 22003 from the casts
            -- below): an integer one infinite or beyond the type once truncated; a real one finite that float4 makes
            -- infinite (from half an ulp above its largest value), or non-zero that it makes 0 (up to 2^-150)
            SELECT string_agg(format('SELECT format(''region %%s: %s property %s (%s) value %%s at ids %%s'', s.region,
                                         min(s.x), tgsis.merge_ids_text(array_agg(s.id::text ORDER BY s.id)))
                                        FROM (SELECT s.region, s.id, s.vals[array_position(s.cols, %L)] AS x
                                                FROM pg_temp.%I s) AS s
                                       WHERE s.x <> ''NaN'' AND %s
                                       GROUP BY s.region',
                                     v_side.word, quote_ident(a.attname), format_type(a.atttypid, a.atttypmod), a.attname,
                                     v_side.work,
                                     CASE WHEN a.atttypid = 'real'::regtype
                                          THEN 'abs(s.x) <> ''Infinity'' AND (abs(s.x) >= 3.4028235677973366e38::float8'
                                               ' OR (s.x <> 0 AND abs(s.x) <= 7.006492321624085e-46::float8))'
                                          ELSE format('NOT (trunc(s.x) >= %s::float8 AND trunc(s.x) < %s::float8)',
                                                      -(2::numeric ^ (8 * a.attlen - 1)), 2::numeric ^ (8 * a.attlen - 1)) END),
                              ' UNION ALL ' ORDER BY a.attnum)
              INTO v_why
              FROM pg_catalog.pg_attribute a
             WHERE a.attrelid = format('%I.%I', v_side.s, v_side.t)::regclass AND a.attnum > 0 AND NOT a.attisdropped
               AND a.atttypid IN ('smallint'::regtype, 'integer'::regtype, 'bigint'::regtype, 'real'::regtype)
               AND a.attname NOT IN ('_geoid', '_times', '_timem', '_timet', '_idx');
            IF v_why IS NOT NULL THEN
                EXECUTE format('SELECT string_agg(w, ''; '') FROM (%s) AS q(w)', v_why) INTO v_why;
            END IF;
            IF v_why IS NOT NULL THEN
                RAISE EXCEPTION '%: its solution rows hold values a column cannot hold (%)', p_refused, v_why
                    USING ERRCODE = 'TG302',
                          HINT = 'record the solution again with values the columns hold (tgsis.resolve_region), or solve the object as a whole (tgsis.resolve_conflict)';
            END IF;
            SELECT 'ARRAY[' || string_agg(
                       CASE WHEN a.atttypid IN ('real'::regtype, 'double precision'::regtype)
                            THEN format('(s.vals[array_position(s.cols, %L)] + 0::float8)::text', a.attname)
                            ELSE format('(SELECT CASE WHEN x = ''NaN'' THEN ''NaN'' WHEN x = trunc(x) AND abs(x) < 9e18'
                                        ' THEN x::bigint::text ELSE x::text END FROM (SELECT s.vals[array_position(s.cols, %L)] AS x) AS x)',
                                        a.attname) END, ', ' ORDER BY a.attnum) || ']::text',
                   'ARRAY[' || string_agg(
                       CASE WHEN a.atttypid = 'double precision'::regtype
                            THEN format('s.vals[array_position(s.cols, %L)]::text', a.attname)
                            WHEN a.atttypid = 'real'::regtype
                            THEN format('s.vals[array_position(s.cols, %L)]::real::text', a.attname)
                            ELSE format('(SELECT CASE WHEN x <> ''NaN'' THEN trunc(x)::bigint::text END'
                                        ' FROM (SELECT s.vals[array_position(s.cols, %L)] AS x) AS x)', a.attname) END,
                       ', ' ORDER BY a.attnum) || ']'
              INTO v_canon, v_write
              FROM pg_catalog.pg_attribute a
             WHERE a.attrelid = format('%I.%I', v_side.s, v_side.t)::regclass AND a.attnum > 0 AND NOT a.attisdropped
               AND a.attname NOT IN ('_geoid', '_times', '_timem', '_timet', '_idx');
            EXECUTE format('UPDATE pg_temp.%I s SET val = %s, w = %s', v_side.work, v_canon, v_write);
            -- the base's values of the ids no state changed
            DROP TABLE IF EXISTS pg_temp.tgsis_mw_bval;
            EXECUTE format('CREATE TEMPORARY TABLE tgsis_mw_bval ON COMMIT DROP AS
                            SELECT r.key, r.val FROM tgsis.versioned_tables t,
                                   tgsis.merge_property_rows(t, $1, NULL, ARRAY(SELECT s.id FROM pg_temp.%I s WHERE s.based),
                                                             $2, $2, $2, $3, $4) AS r
                             WHERE t.schemaname = %L AND t.tablename = %L AND r.seen & 1 <> 0', v_side.work, v_side.s, v_side.t)
              USING p_geoid, v_info.base, v_info.times, v_info.timem;
            EXECUTE format('UPDATE pg_temp.%I s SET bval = coalesce((SELECT r.val FROM pg_temp.tgsis_mw_bval r WHERE r.key = s.id),
                                                           (SELECT nulls FROM tgsis.merge_value_text(%L, %L)))
                             WHERE s.based', v_side.work, v_side.s, v_side.t);
        END IF;
    END LOOP;
    -- an atom's refid is a vertex id and a part a part number: a value of neither (5.5: the cast rounded it where
    -- the Python writer truncates; beyond the column) is refused, as the Python writer refuses it
    SELECT string_agg(format('region %s: %s %s at ids %s', q.region, q.what, q.val, tgsis.merge_ids_text(q.ids)), '; '
                      ORDER BY q.region, q.what)
      INTO v_why
      FROM (SELECT s.region, 'refid' AS what, min(s.x) AS val, array_agg(s.id::text ORDER BY s.id) AS ids
              FROM (SELECT s.region, s.id, s.vals[array_position(s.cols, 'refid')] AS x FROM pg_temp.tgsis_mw_sv s) AS s
             WHERE s.x >= 0 AND s.x <> 'NaN' AND (s.x <> trunc(s.x) OR s.x >= 9223372036854775808::float8)
             GROUP BY s.region
            UNION ALL
            SELECT s.region, 'part', min(s.x), array_agg(s.id::text ORDER BY s.id)
              FROM (SELECT s.region, s.id, s.vals[array_position(s.cols, 'part')] AS x FROM pg_temp.tgsis_mw_sc s) AS s
             WHERE s.x >= 0 AND s.x <> 'NaN' AND (s.x <> trunc(s.x) OR s.x >= 2147483648::float8)
             GROUP BY s.region) AS q;
    IF v_why IS NOT NULL THEN
        RAISE EXCEPTION '%: its solution rows hold atoms'' refid or cell parts that are no whole vertex ids or part numbers (%)',
                p_refused, v_why
            USING ERRCODE = 'TG302',
                  HINT = 'record the solution again with whole numbers (tgsis.resolve_region), or solve the object as a whole (tgsis.resolve_conflict)';
    END IF;
    UPDATE pg_temp.tgsis_mw_sv s SET ref = s.vals[array_position(s.cols, 'refid')]::bigint
     WHERE s.vals[array_position(s.cols, 'refid')] >= 0
       AND s.vals[array_position(s.cols, 'refid')] < 9223372036854775808::float8;  -- (NaN is above every number)
    UPDATE pg_temp.tgsis_mw_sc s SET part = s.vals[array_position(s.cols, 'part')]::bigint
     WHERE s.vals[array_position(s.cols, 'part')] >= 0
       AND s.vals[array_position(s.cols, 'part')] < 2147483648::float8;

    -- a row of an id no state changed inside its region: the solution's (merge3 takes a manual state's rows of the
    -- region's ids), the base's row closed (tgsis.merge_mesh_by_region) when it differs or is gone; one as the base
    -- has it stays. An id inside that no state has cannot be (the region's ids are the states'): refused
    SELECT string_agg(format('region %s: %s %s (in no state)', q.region, q.what, tgsis.merge_ids_text(q.ids)), '; '
                      ORDER BY q.region, q.what) INTO v_why
      FROM (SELECT s.region, 'vertices' AS what, array_agg(s.id::text ORDER BY s.id) AS ids FROM pg_temp.tgsis_mw_sv s
             WHERE s.inside AND NOT s.changed AND NOT s.based GROUP BY s.region
            UNION ALL
            SELECT s.region, 'cells', array_agg(s.id::text ORDER BY s.id) FROM pg_temp.tgsis_mw_sc s
             WHERE s.inside AND NOT s.changed AND NOT s.based GROUP BY s.region) AS q;
    IF v_why IS NOT NULL THEN
        RAISE EXCEPTION '%: its solution gives rows of its regions no state has (%)', p_refused, v_why
            USING ERRCODE = 'TG302', HINT = p_hint;
    END IF;
    DELETE FROM pg_temp.tgsis_mw_sv s
     WHERE s.inside AND NOT s.changed AND NOT s.gone AND float8send(s.x) = float8send(s.b_x)
       AND float8send(s.y) = float8send(s.b_y) AND float8send(s.z) = float8send(s.b_z)
       AND s.val IS NOT DISTINCT FROM s.bval AND s.ref IS NOT DISTINCT FROM s.bref;
    DELETE FROM pg_temp.tgsis_mw_sc s
     WHERE s.inside AND NOT s.changed AND NOT s.gone AND s.v = s.bv AND s.val IS NOT DISTINCT FROM s.bval
       AND (NOT v_info.runs OR s.part IS NOT DISTINCT FROM s.bpart);

    -- the rows outside its region that are no new id and not another such region's: the merged state's, or refused
    -- (merge3: the manual mesh of region r changes rows outside the region)
    SELECT string_agg(format('the solution of region %s changes rows outside the region: %s', q.region, q.what), '; '
                      ORDER BY q.region) INTO v_why
      FROM (SELECT s.region, format('vertices %s', tgsis.merge_ids_text(array_agg(s.id::text ORDER BY s.id))) AS what
              FROM pg_temp.tgsis_mw_sv s LEFT JOIN pg_temp.tgsis_mw_v n ON n.id = s.id
             WHERE NOT s.inside AND (s.changed OR s.based)
               AND NOT EXISTS (SELECT FROM pg_temp.tgsis_mw_node o JOIN pg_temp.tgsis_mw_region g ON g.region = o.region
                                WHERE g.src = 8 AND o.kind = 'v' AND o.id = s.id)
               AND NOT CASE WHEN s.changed
                            THEN coalesce(n.present AND float8send(s.x) = float8send(n.x) AND float8send(s.y) = float8send(n.y)
                                          AND float8send(s.z) = float8send(n.z) AND s.val IS NOT DISTINCT FROM n.val
                                          AND s.ref IS NOT DISTINCT FROM n.ref, false)
                            ELSE float8send(s.x) = float8send(s.b_x) AND float8send(s.y) = float8send(s.b_y)
                                 AND float8send(s.z) = float8send(s.b_z) AND s.val IS NOT DISTINCT FROM s.bval
                                 AND s.ref IS NOT DISTINCT FROM s.bref END
             GROUP BY s.region
            UNION ALL
            SELECT s.region, format('cells %s', tgsis.merge_ids_text(array_agg(s.id::text ORDER BY s.id)))
              FROM pg_temp.tgsis_mw_sc s LEFT JOIN pg_temp.tgsis_mw_c n ON n.id = s.id
             WHERE NOT s.inside AND (s.changed OR s.based)
               AND NOT EXISTS (SELECT FROM pg_temp.tgsis_mw_node o JOIN pg_temp.tgsis_mw_region g ON g.region = o.region
                                WHERE g.src = 8 AND o.kind = 'c' AND o.id = s.id)
               AND NOT CASE WHEN s.changed
                            THEN coalesce(n.present AND s.v = n.v AND s.val IS NOT DISTINCT FROM n.val
                                          AND s.part IS NOT DISTINCT FROM n.part, false)
                            ELSE s.v = s.bv AND s.val IS NOT DISTINCT FROM s.bval
                                 AND (NOT v_info.runs OR s.part IS NOT DISTINCT FROM s.bpart) END
             GROUP BY s.region) AS q;
    IF v_why IS NOT NULL THEN
        RAISE EXCEPTION '%: %', p_refused, v_why
            USING ERRCODE = 'TG302',  -- (the Python merge: TG100; in SQL a TG100 of the merge is a bigint overflow)
                  HINT = 'a manual mesh replaces its region''s rows (and may add rows of new ids); solve the other regions on their own';
    END IF;
    -- what is taken: the region's rows and the new ids
    DELETE FROM pg_temp.tgsis_mw_sv s WHERE NOT s.inside AND (s.changed OR s.based);
    DELETE FROM pg_temp.tgsis_mw_sc s WHERE NOT s.inside AND (s.changed OR s.based);
    -- a new id two solutions both give would be two rows: refused (nothing tells which is meant)
    SELECT string_agg(q.what, '; ') INTO v_why
      FROM (SELECT format('vertex %s given by regions %s', s.id, string_agg(s.region::text, ', ' ORDER BY s.region)) AS what
              FROM pg_temp.tgsis_mw_sv s GROUP BY s.id HAVING count(*) > 1
            UNION ALL
            SELECT format('cell %s given by regions %s', s.id, string_agg(s.region::text, ', ' ORDER BY s.region))
              FROM pg_temp.tgsis_mw_sc s GROUP BY s.id HAVING count(*) > 1) AS q;
    IF v_why IS NOT NULL THEN
        RAISE EXCEPTION '%: the solutions of two regions give rows of the same new id (%)', p_refused, v_why
            USING ERRCODE = 'TG302', HINT = p_hint;
    END IF;
END
$$;

COMMENT ON FUNCTION tgsis.merge_solution_rows(bigint, integer, text, text) IS
    'for tgsis.merge_mesh_by_region: the rows the average and manual solutions (recorded with their rows, tgsis.conflict_regions.solution_*) give a feature, in pg_temp.tgsis_mw_sv / tgsis_mw_sc, checked as tgsis.merge3.apply_solutions checks a manual state (TG302 otherwise)';

-- internal to the psql merge by region (reached only through the SECURITY DEFINER merge, find_conflicts and
-- resolve functions): not executable by PUBLIC, like tgsis's other internal helpers
REVOKE ALL ON FUNCTION tgsis.merge_solution_rows(bigint, integer, text, text) FROM PUBLIC;
