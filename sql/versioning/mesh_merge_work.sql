-- tgsis.mesh_merge_work(version, geoid): the work tables of the three-way merge of one model-1 mesh, in SQL.
-- What tgsis.mesh_merge_regions summarises (the regions) and what the SQL merge by region
-- writes from: the tables are made in pg_temp and left to the caller, who runs this in a
-- subtransaction it rolls back once it has what it needs (neither the tables nor their locks should
-- outlive a call: about 100 locks each). No subtransaction of its own.
-- The regions tgsis.merge3.three_way_merge finds (docs/merge.md, "Regions"),
-- computed set-based from the storage, so that a psql user's
-- tgsis.find_conflicts records them without the Python client (issue 39,
-- items 2 and 4). The three states are the object at the version's
-- initrevision (base), in the parent's and in the version's working sets;
-- only the rows whose visibility differs between the three sets are read
-- (revision or lastrevs in the symmetric difference of the sets, as the
-- Python reader reads them), then, by key, every row of those keys seen by a
-- set: the vertices (tgsis.vrtx, GOCAD atoms as the vertex value refid, the
-- vertex properties), the cells (the class's simplex table, the cell
-- properties, parts kept in tgsis.part as the cell value part). Rows of other
-- keys are the same in the three states. Model-1 tables stored in chunks (issue 40) are read
-- through their decoded chunk versions (tgsis.storage_row_versions); their changed keys are the slots of
-- the chunks written or closed in those revisions whose values (bit for bit) or presence differ between
-- the three states (tgsis.storage_changed_rows), so the work is sized by the change, as on rows; so are
-- model 2's at an instant and model 3's at a geometry instant (since the twenty-first session).
-- Then, as merge3 does:
--   * the version's new ids are renumbered (merge3's child renumbering: a new
--     row with the content of a parent's new row takes its id, pairing the
--     k-th of equal contents with the k-th; a new id the parent uses for
--     something else takes a fresh one above every id, ascending);
--   * each side's edit against the base: vertices moved, added, removed, or a
--     value changed; cells added, removed, reconnected (an odd permutation is
--     a reconnection: tgsis.oriented_cell_key), or a value changed; values
--     compare as merge3 compares them (NaN equals NaN and a missing row,
--     -0.0 equals 0.0);
--   * each side's footprint: its changed vertices and cells, the base cells
--     on a vertex it moved, added or removed (found through the vertex BRIN
--     of the cell storage, by a few spans of those vertex ids), the
--     vertices of the cells it added, removed or reconnected;
--   * regions: connected components of the footprints' vertices and cells
--     (a cell and a vertex of its row, base's or the side's, both in one
--     side's footprint), by union-find over the few changed elements (one
--     pass over their edges in arrays; each component's root is its least
--     element), numbered as merge3 numbers them (by their first element:
--     vertices ascending, then cells ascending);
--   * per region: its ids, each side's changed ids, a box over its vertices
--     and its cells' corners in the three states, the largest displacement of
--     each side, whether it is a conflict (both sides changed it and their
--     rows differ), and what each whole-region solution discards of each side
--     (discards: {"parent": {"child": [vertices, cells, largest displacement]},
--     "child": {"parent": [...]}, "base": {"parent": [...], "child": [...]}},
--     merge3's RegionDiscard).
-- p_times (model 2, a surface at instants): the same work for one instant of the object, a slice
-- tgsis._merge_slices merges by merge3: the rows of tgsis.times_vrtx / times_trgl and of the property
-- tables keyed (_times, _idx) at that instant, the margin, the base's coordinates and the largest ids
-- (the renumbering's fresh ids: Python's per-slice top_ids) of that instant alone; no GOCAD atoms, no
-- part runs. The object-level refusals (tgsis.region_merge_refusal) are the caller's then: an instant
-- the three states have, of an object merged instant by instant (tgsis.merge_instants_by_slice).
-- p_timem with p_times (model 3, an evolving surface): the same for the geometry instant p_times of the
-- topology period starting at p_timem, the slice tgsis._merge_slices merges there: the nodes' rows of
-- tgsis.d4dvrtx at that geometry instant (their ids the vertex ids), the period's triangles
-- (tgsis.d4dtrgl), the property rows keyed (_timem, _timet, _idx); the largest ids those of the geometry
-- instant's nodes and of the period's triangles (Python's per-slice top_ids).
-- The work tables (ON COMMIT DROP, dropped first if an earlier call left them):
--   tgsis_mr_info   one row: version, parent, the three revision sets, the class, its cell table,
--                   cell id column, vertices per cell, property tables, whether parts are runs;
--   tgsis_mr_v/_c   the rows of the changed keys per state (st 1 base, 2 parent, 4 version), the
--                   version's rows renumbered; tgsis_mr_vmap/_cmap the renumbering (old, new);
--   tgsis_mr_vx/_cx per id, each state's row and each side's edit; tgsis_mr_margin the base's cells on
--                   a vertex whose shape changed; tgsis_mr_fv/_fc the footprints; tgsis_mr_node the
--                   footprints' elements labelled by region (label: least node of the component);
--   tgsis_mr_edge   the footprint graph; tgsis_mr_vb the base's coordinates of the other vertices a
--                   region touches.
-- Returns the number of footprint elements (0: no region; tgsis_mr_edge and tgsis_mr_vb are then
-- not made). A role that may not read the
-- feature's class is refused (42501): regions computed without its rows
-- would be wrong. A feature not changed on both sides is refused (TG300),
-- one that does not merge by region (tgsis.region_merge_refusal: deleted on
-- one side, ...) too (TG100), as the Python reader refuses them. extra_float_digits is pinned: values are
-- compared as text, floats exactly; client_min_messages too: dropping the
-- work tables of an earlier call says nothing.
CREATE FUNCTION tgsis.mesh_merge_work(p_version text, p_geoid bigint, p_times float8 DEFAULT NULL,
                                      p_timem float8 DEFAULT NULL)
RETURNS integer
LANGUAGE plpgsql
VOLATILE
SET search_path = pg_catalog, pg_temp
SET extra_float_digits = 1
SET client_min_messages = warning
AS $$
#variable_conflict use_column
DECLARE
    v_version tgsis.versions;
    v_parent  tgsis.versions;
    v_base    integer[];
    v_since   integer[];
    v_refusal text;
    v_class   tgsis.catalog;
    v_table   text;
    v_cellid  text;
    v_k       integer;
    v_row     text;
    v_seen    text;
    v_changed text;
    v_vpt     tgsis.versioned_tables;
    v_cpt     tgsis.versioned_tables;
    v_vcanon  text;
    v_ccanon  text;
    v_vnull   text;
    v_cnull   text;
    v_runs    boolean;
    v_narrow  boolean;  -- the changed keys from the slots that differ (tgsis.storage_changed_rows)
    v_vkeys   bigint[];
    v_ckeys   bigint[];
    v_top_v   bigint;
    v_top_c   bigint;
    v_shape   bigint[];
    v_up      integer[];
    v_ea      integer[];
    v_eb      integer[];
    v_x       integer;
    v_y       integer;
    v_obj     text := 'v.geoid = $1';
    v_cobj    text;
    v_vsrc    text;
    v_csrc    text;
    v_vkeyed  text;
    v_ckeyed  text;
    v_ids     bigint[];
    v_top     text[];
    v_last    bigint;
    v_atoms   text := '';
    v_lo      bigint[];
    v_hi      bigint[];
BEGIN
    SELECT * INTO v_version FROM tgsis.versions WHERE versionid = tgsis.version_id(p_version);
    IF v_version.parentid IS NULL THEN
        RAISE EXCEPTION 'version DEFAULT has no parent to merge with' USING ERRCODE = 'TG100',
            HINT = 'give the name of a version made by create_version';
    END IF;
    IF p_geoid IN (SELECT tgsis.class_denied_geoids('SELECT')) THEN
        RAISE EXCEPTION 'role % may not read feature % (its class): its regions cannot be computed',
                quote_ident(tgsis.calling_role()), p_geoid
            USING ERRCODE = '42501', HINT = 'the class''s owner can GRANT SELECT on its feature table';
    END IF;
    IF NOT EXISTS (SELECT FROM tgsis.current_conflicts(v_version.versionid) AS k
                    WHERE k.objectclass = 'feature' AND k.objectkey = p_geoid::text) THEN
        RAISE EXCEPTION 'feature % was not changed both in version % and in its parent since the version was based: there is nothing to merge',
                p_geoid, quote_literal(p_version)
            USING ERRCODE = 'TG300', HINT = format('SELECT * FROM tgsis.find_conflicts(%L) lists the objects changed on both sides', p_version);
    END IF;
    IF p_timem IS NOT NULL AND p_times IS NULL THEN
        RAISE EXCEPTION 'tgsis.mesh_merge_work: the period % of feature % given without a geometry instant', p_timem, p_geoid
            USING ERRCODE = '22023', HINT = 'give the geometry instant (timet) as p_times, the period (timem) as p_timem';
    END IF;
    IF p_timem IS NOT NULL THEN  -- one geometry instant of an evolving surface: the caller asked the object-level refusals
        v_refusal := CASE WHEN (SELECT c.timemodel FROM tgsis.catalog c WHERE c.classname = tgsis.class_of_geoid(p_geoid))
                               IS DISTINCT FROM 'EVOLVING'
                          THEN format('feature %s is not an evolving surface (model 3): it has no geometry instant %s of a period starting at %s',
                                      p_geoid, p_times, p_timem) END;
        v_refusal := coalesce(v_refusal, tgsis.object_merge_refusal(p_version, p_geoid));
    ELSIF p_times IS NOT NULL THEN  -- one instant of a surface at instants: the caller asked the object-level refusals
        v_refusal := CASE WHEN (SELECT c.timemodel FROM tgsis.catalog c WHERE c.classname = tgsis.class_of_geoid(p_geoid))
                               IS DISTINCT FROM 'INSTANTS'
                          THEN format('feature %s is not a surface at instants (model 2): it has no instant %s', p_geoid, p_times) END;
        v_refusal := coalesce(v_refusal, tgsis.object_merge_refusal(p_version, p_geoid));
    ELSE
        v_refusal := tgsis.region_merge_refusal(p_version, p_geoid);
    END IF;
    IF v_refusal IS NOT NULL THEN  -- the Python reader's InvalidInputError, with its code
        RAISE EXCEPTION 'feature % does not merge by region in version %: %', p_geoid, quote_literal(p_version), v_refusal
            USING ERRCODE = 'TG100',
                  DETAIL = 'The merge by region merges the mesh of a static feature changed on both sides.',
                  HINT = format('solve it as a whole object: SELECT tgsis.resolve_conflict(%L, ''feature'', %L, ''parent''|''child''|''manual'')',
                                p_version, p_geoid::text);
    END IF;
    -- the work, in a subtransaction rolled back once the regions are in v_out: neither the work tables nor
    -- the locks on them outlive the call (a relation created and dropped keeps its lock until the
    -- transaction ends: about 100 per call, and a find_conflicts over many meshes ran out of the shared
    -- lock table). The block's body is not indented.
    SELECT * INTO v_parent FROM tgsis.versions WHERE versionid = v_version.parentid;
    v_base := tgsis.revision_set(v_version.versionid, v_version.initrevision);
    v_since := ARRAY(SELECT r FROM unnest(v_base || v_parent.workingset || v_version.workingset) AS r
                     EXCEPT SELECT r FROM unnest(v_base) AS r WHERE r = ANY (v_parent.workingset) AND r = ANY (v_version.workingset)
                     ORDER BY 1);
    SELECT c.* INTO v_class FROM tgsis.catalog c WHERE c.classname = tgsis.class_of_geoid(p_geoid);
    IF p_timem IS NOT NULL
       AND (SELECT count(*) FROM (VALUES (v_base), (v_parent.workingset), (v_version.workingset)) AS s (revs)
             WHERE EXISTS (SELECT FROM tgsis.timet_ver v WHERE v.geoid = p_geoid AND v.timem = p_timem AND v.timet = p_times
                              AND v.revision = ANY (s.revs) AND NOT (v.revclosed AND v.lastrevs && s.revs))) < 3 THEN
        RAISE EXCEPTION 'feature % does not merge by region at geometry instant % of the period starting at % in version %: the geometry instant is not in all three states (base, parent, version)',
                p_geoid, p_times, p_timem, quote_literal(p_version)
            USING ERRCODE = 'TG100',
                  DETAIL = 'A period or geometry instant added or removed on a side is taken from that side as a whole, or is an object-level conflict.',
                  HINT = format('SELECT tgsis.merge_version(%L) merges it period by period', p_version);
    END IF;
    IF p_timem IS NULL AND p_times IS NOT NULL
       AND (SELECT count(*) FROM (VALUES (v_base), (v_parent.workingset), (v_version.workingset)) AS s (revs)
             WHERE EXISTS (SELECT FROM tgsis.times_ver v WHERE v.geoid = p_geoid AND v.times = p_times
                              AND v.revision = ANY (s.revs) AND NOT (v.revclosed AND v.lastrevs && s.revs))) < 3 THEN
        RAISE EXCEPTION 'feature % does not merge by region at instant % in version %: the instant is not in all three states (base, parent, version)',
                p_geoid, p_times, quote_literal(p_version)
            USING ERRCODE = 'TG100',
                  DETAIL = 'An instant added or removed on a side is taken from that side as a whole, or is an object-level conflict.',
                  HINT = format('SELECT tgsis.merge_version(%L) merges it instant by instant', p_version);
    END IF;
    v_table := tgsis.simplex_table(v_class.geotype);
    v_cellid := CASE v_table WHEN 'point' THEN 'pointid' WHEN 'segment' THEN 'segid' WHEN 'trgl' THEN 'trglid' ELSE 'tetraid' END;
    v_k := CASE v_table WHEN 'point' THEN 1 WHEN 'segment' THEN 2 WHEN 'trgl' THEN 3 ELSE 4 END;
    IF p_times IS NULL THEN
        v_atoms := 'UNION SELECT v.vrtxid FROM tgsis.atom_ver v WHERE v.geoid = $1 AND %1$s';
    ELSIF p_timem IS NULL THEN  -- the slice: the instant's rows of the model-2 tables (no GOCAD atoms, no part runs there)
        v_table := 'times_trgl';
        v_cellid := 'trglid';
        v_k := 3;
        v_vsrc := tgsis.storage_row_versions('tgsis', 'times_vrtx');  -- (decoded chunk versions when stored in chunks)
        v_csrc := tgsis.storage_row_versions('tgsis', 'times_trgl');
        v_obj := format('v.geoid = $1 AND v.times = %L::float8', p_times);
    ELSE  -- model 3: the period's nodes at the geometry instant (d4dvrtx), the period's triangles (d4dtrgl), their
          -- node columns named as the other models' vertex columns (simple subqueries: planned as the tables)
        v_table := 'd4dtrgl';
        v_cellid := 'trglid';
        v_k := 3;
        -- (decoded chunk versions when stored in chunks: tgsis.storage_row_versions)
        v_vsrc := format('(SELECT w.geoid, w.timem, w.timet, w.nodeid AS vrtxid, w.x, w.y, w.z, w.revision, w.revclosed, w.lastrevs
                             FROM %s w)', tgsis.storage_row_versions('tgsis', 'd4dvrtx'));
        v_csrc := format('(SELECT w.geoid, w.timem, w.trglid, w.nodeid1 AS vrtxid1, w.nodeid2 AS vrtxid2, w.nodeid3 AS vrtxid3,
                                  w.revision, w.revclosed, w.lastrevs FROM %s w)', tgsis.storage_row_versions('tgsis', 'd4dtrgl'));
        v_obj := format('v.geoid = $1 AND v.timem = %L::float8 AND v.timet = %L::float8', p_timem, p_times);
        v_cobj := format('v.geoid = $1 AND v.timem = %L::float8', p_timem);
    END IF;
    IF p_times IS NULL THEN  -- model 1: the rows of the storage, decoded chunk versions when stored in chunks
        v_vsrc := tgsis.storage_row_versions('tgsis', 'vrtx');
        v_csrc := tgsis.storage_row_versions('tgsis', v_table);
    END IF;
    v_csrc := coalesce(v_csrc, format('tgsis.%I', v_table || '_ver'));
    v_cobj := coalesce(v_cobj, v_obj);
    v_row := format('ARRAY[%s]', (SELECT string_agg(format('v.vrtxid%s', i), ', ') FROM generate_series(1, v_k) AS i));
    v_changed := '(v.revision = ANY ($2) OR (v.revclosed AND v.lastrevs && $2))';

    -- the property tables of vertices and cells, with each row's values as one canonical text
    SELECT t.* INTO v_vpt FROM tgsis.versioned_tables t
     WHERE t.schemaname = v_class.schemaname
       AND t.tablename = CASE v_class.proalignment WHEN 'VERTEX' THEN v_class.cellprotable ELSE v_class.otherprotable END;
    SELECT t.* INTO v_cpt FROM tgsis.versioned_tables t
     WHERE t.schemaname = v_class.schemaname
       AND t.tablename = CASE v_class.proalignment WHEN 'CELL' THEN v_class.cellprotable ELSE v_class.otherprotable END;
    SELECT canon, nulls INTO v_vcanon, v_vnull FROM tgsis.merge_value_text(v_vpt.schemaname, v_vpt.tablename);
    SELECT canon, nulls INTO v_ccanon, v_cnull FROM tgsis.merge_value_text(v_cpt.schemaname, v_cpt.tablename);
    v_runs := p_times IS NULL
              AND NOT EXISTS (SELECT FROM jsonb_array_elements(v_class.cell_properties) AS e
                               WHERE e ->> 'name' = 'part' AND coalesce(e ->> 'alignment', v_class.proalignment) = 'CELL');


    DROP TABLE IF EXISTS pg_temp.tgsis_mr_v, pg_temp.tgsis_mr_c, pg_temp.tgsis_mr_vmap, pg_temp.tgsis_mr_cmap,
                         pg_temp.tgsis_mr_vx, pg_temp.tgsis_mr_cx, pg_temp.tgsis_mr_margin, pg_temp.tgsis_mr_fv,
                         pg_temp.tgsis_mr_fc, pg_temp.tgsis_mr_node, pg_temp.tgsis_mr_edge, pg_temp.tgsis_mr_vb,
                         pg_temp.tgsis_mr_info;

    CREATE TEMPORARY TABLE tgsis_mr_info ON COMMIT DROP AS
    SELECT v_version.versionid AS versionid, v_parent.versionid AS parentid, v_base AS base,
           v_parent.workingset AS parentset, v_version.workingset AS versionset, v_since AS since,
           v_class.classname AS classname, v_table AS simplex, v_cellid AS cellid, v_k AS k,
           v_vpt.schemaname AS vpschema, v_vpt.tablename AS vptable, v_cpt.schemaname AS cpschema,
           v_cpt.tablename AS cptable, v_runs AS runs, p_times AS times, p_timem AS timem;


    -- 1. the keys of the rows some set sees otherwise than another ($2: the revisions that tell the sets apart;
    -- model 1, and model 2's instant (its chunks keyed by instant, tgsis.chunk_key), stored in chunks: only the
    -- slots of the changed chunks whose values or presence differ between the three states,
    -- tgsis.storage_changed_rows, so that the work is sized by the change, not by its chunks; model 2's keys
    -- are those tgsis.merge_instants_by_slice reads, the same way, and the two must agree: the merged rows of
    -- the one are compared with the version's rows of the other; an instant whose tgsis.times row changed, added
    -- or removed somewhere, is read whole there, so here every slot of its changed chunks, as before)
    -- model 3's geometry instant likewise (d4dvrtx's chunks keyed by geometry instant, d4dtrgl's by period), its keys
    -- those tgsis.merge_periods_by_slice reads; a period whose tgsis.timem or tgsis.timet rows changed (removed and
    -- added anew somewhere) is read whole there, so here every slot of its changed chunks)
    v_narrow := CASE WHEN p_timem IS NOT NULL
                     THEN NOT EXISTS (SELECT FROM tgsis.timem_ver v WHERE v.geoid = p_geoid AND v.timem = p_timem
                                         AND (v.revision = ANY (v_since) OR (v.revclosed AND v.lastrevs && v_since)))
                          AND NOT EXISTS (SELECT FROM tgsis.timet_ver v WHERE v.geoid = p_geoid AND v.timem = p_timem
                                             AND (v.revision = ANY (v_since) OR (v.revclosed AND v.lastrevs && v_since)))
                     ELSE p_times IS NULL
                          OR NOT EXISTS (SELECT FROM tgsis.times_ver v WHERE v.geoid = p_geoid AND v.times = p_times
                                            AND (v.revision = ANY (v_since) OR (v.revclosed AND v.lastrevs && v_since))) END;
    EXECUTE format('SELECT ARRAY(SELECT v.vrtxid FROM %2$s v WHERE %3$s AND %1$s ' || v_atoms || ')',
                   v_changed,
                   CASE WHEN NOT v_narrow THEN v_vsrc
                        WHEN p_timem IS NOT NULL  -- (the nodes' columns named as the vertices', as v_vsrc names them)
                        THEN format('(SELECT w.geoid, w.timem, w.timet, w.nodeid AS vrtxid, w.revision, w.revclosed, w.lastrevs
                                       FROM %s w)',
                                    tgsis.storage_changed_rows('tgsis', 'd4dvrtx', ARRAY[p_geoid], v_base,
                                                               v_parent.workingset, v_version.workingset))
                        ELSE tgsis.storage_changed_rows('tgsis', CASE WHEN p_times IS NULL THEN 'vrtx' ELSE 'times_vrtx' END,
                                                        ARRAY[p_geoid], v_base, v_parent.workingset, v_version.workingset) END,
                   v_obj)
       INTO v_vkeys USING p_geoid, v_since;
    EXECUTE format('SELECT ARRAY(SELECT v.%1$I FROM %2$s v WHERE %4$s AND %3$s)',
                   v_cellid,
                   CASE WHEN v_narrow
                        THEN tgsis.storage_changed_rows('tgsis', v_table, ARRAY[p_geoid], v_base, v_parent.workingset,
                                                        v_version.workingset)
                        ELSE v_csrc END,
                   v_changed, v_cobj)
       INTO v_ckeys USING p_geoid, v_since;
    IF v_vcanon IS NOT NULL THEN
        v_vkeys := v_vkeys || ARRAY(SELECT r.key FROM tgsis.merge_property_rows(v_vpt, p_geoid, v_since, NULL, NULL, NULL, NULL, p_times, p_timem) AS r);
    END IF;
    IF v_ccanon IS NOT NULL THEN
        v_ckeys := v_ckeys || ARRAY(SELECT r.key FROM tgsis.merge_property_rows(v_cpt, p_geoid, v_since, NULL, NULL, NULL, NULL, p_times, p_timem) AS r);
    END IF;
    IF v_runs THEN
        -- the cells whose part some state sees otherwise: those of the id spans where the runs the three states
        -- see (tgsis.part, a few rows per object) give another part, or more than one, in some state (the runs'
        -- ends cut the ids into spans each run covers whole or not at all; a run no set sees otherwise is in
        -- every state or none and changes nothing). A rewrite of every run of the object (as a check-in writes
        -- them) that changes one run leaves that run's span only. Then the cells of those spans only: stored in
        -- chunks, the chunks that hold them (not every cell version of the object)
        WITH r AS (
            SELECT v.firstid, v.lastid, v.part,
                   (v.revision = ANY (v_base) AND NOT (v.revclosed AND v.lastrevs && v_base))::integer
                   | ((v.revision = ANY (v_parent.workingset) AND NOT (v.revclosed AND v.lastrevs && v_parent.workingset))::integer << 1)
                   | ((v.revision = ANY (v_version.workingset) AND NOT (v.revclosed AND v.lastrevs && v_version.workingset))::integer << 2)
                       AS seen
              FROM tgsis.part_ver v
             WHERE v.geoid = p_geoid AND v.firstid <= v.lastid),
        b AS (
            SELECT DISTINCT p.x FROM r CROSS JOIN LATERAL (VALUES (r.firstid),
                                                                 (CASE WHEN r.lastid < 9223372036854775807 THEN r.lastid + 1 END)) AS p (x)
             WHERE r.seen <> 0 AND p.x IS NOT NULL),
        -- (the last span: to the end of bigint, kept only if a run reaches it)
        e AS (SELECT b.x AS lo, coalesce(lead(b.x) OVER (ORDER BY b.x) - 1, 9223372036854775807) AS hi FROM b)
        SELECT coalesce(array_agg(e.lo ORDER BY e.lo), '{}'), coalesce(array_agg(e.hi ORDER BY e.lo), '{}')
          INTO v_lo, v_hi
          FROM e CROSS JOIN LATERAL (
                   SELECT array_agg(r.part ORDER BY r.part) FILTER (WHERE r.seen & 1 <> 0) AS p1,
                          array_agg(r.part ORDER BY r.part) FILTER (WHERE r.seen & 2 <> 0) AS p2,
                          array_agg(r.part ORDER BY r.part) FILTER (WHERE r.seen & 4 <> 0) AS p4
                     FROM r WHERE r.seen <> 0 AND r.firstid <= e.lo AND r.lastid >= e.lo) AS q
         WHERE (q.p1 IS DISTINCT FROM q.p2 OR q.p1 IS DISTINCT FROM q.p4
                OR cardinality(q.p1) > 1 OR cardinality(q.p2) > 1 OR cardinality(q.p4) > 1);
        IF cardinality(v_lo) > 0 THEN
            IF tgsis.stored_in_chunks(v_table) THEN  -- one id per chunk of the spans: the chunks decoded
                -- (spans wider than the object's chunks, as a run to the end of bigint: its chunks, not a series)
                EXECUTE format('SELECT ARRAY(SELECT DISTINCT c.chunk * t.chunksize
                                               FROM %s c, tgsis.model_tables t, unnest($2, $3) AS u (lo, hi)
                                              WHERE c.geoid = $1 AND t.tablename = $4
                                                AND c.chunk BETWEEN greatest(u.lo, 0) / t.chunksize AND u.hi / t.chunksize)',
                               tgsis.storage_table('tgsis', v_table))
                   INTO v_ids USING p_geoid, v_lo, v_hi, v_table;
            END IF;
            EXECUTE format('SELECT $3 || ARRAY(SELECT c.%1$I FROM %2$s c JOIN unnest($4, $5) AS r (lo, hi)
                                                  ON c.%1$I BETWEEN r.lo AND r.hi
                                               WHERE c.geoid = $1)',
                           v_cellid, tgsis.storage_row_versions('tgsis', v_table, v_ids))
               INTO v_ckeys USING p_geoid, NULL::integer[], v_ckeys, v_lo, v_hi;
        END IF;
    END IF;
    v_vkeys := ARRAY(SELECT DISTINCT k FROM unnest(v_vkeys) AS k);
    v_ckeys := ARRAY(SELECT DISTINCT k FROM unnest(v_ckeys) AS k);
    -- (stored in chunks: only the chunks of those keys decoded; the same relation as v_vsrc / v_csrc on rows)
    v_vkeyed := CASE WHEN p_times IS NULL THEN tgsis.storage_row_versions('tgsis', 'vrtx', v_vkeys) ELSE v_vsrc END;
    v_ckeyed := CASE WHEN p_times IS NULL THEN tgsis.storage_row_versions('tgsis', v_table, v_ckeys) ELSE v_csrc END;

    -- 2. their rows as each state has them (st: 1 base, 2 parent, 4 version), values as canonical texts
    v_seen := '(v.revision = ANY (CASE s.st WHEN 1 THEN $2 WHEN 2 THEN $3 ELSE $4 END)
                AND NOT (v.revclosed AND v.lastrevs && CASE s.st WHEN 1 THEN $2 WHEN 2 THEN $3 ELSE $4 END))';
    CREATE TEMPORARY TABLE tgsis_mr_v (id bigint NOT NULL, st smallint NOT NULL, x float8, y float8, z float8,
                                       val text, ref bigint) ON COMMIT DROP;
    EXECUTE format('INSERT INTO pg_temp.tgsis_mr_v (id, st, x, y, z)
                    SELECT v.vrtxid, s.st, v.x, v.y, v.z FROM %2$s v, (VALUES (1::smallint), (2), (4)) AS s (st)
                     WHERE %3$s AND v.vrtxid = ANY ($5) AND %1$s', v_seen, v_vkeyed, v_obj)
       USING p_geoid, v_base, v_parent.workingset, v_version.workingset, v_vkeys;
    IF p_times IS NULL THEN
    EXECUTE format('UPDATE pg_temp.tgsis_mr_v m SET ref = v.refid
                      FROM tgsis.atom_ver v, (VALUES (1::smallint), (2), (4)) AS s (st)
                     WHERE v.geoid = $1 AND v.vrtxid = m.id AND s.st = m.st AND %s', v_seen)
       USING p_geoid, v_base, v_parent.workingset, v_version.workingset;
    END IF;
    IF v_vcanon IS NOT NULL THEN
        UPDATE pg_temp.tgsis_mr_v m SET val = r.val
          FROM tgsis.merge_property_rows(v_vpt, p_geoid, NULL, v_vkeys, v_base, v_parent.workingset, v_version.workingset, p_times, p_timem) AS r
         WHERE r.key = m.id AND r.seen & m.st <> 0;
        UPDATE pg_temp.tgsis_mr_v m SET val = v_vnull WHERE m.val IS NULL;
    END IF;
    CREATE TEMPORARY TABLE tgsis_mr_c (id bigint NOT NULL, st smallint NOT NULL, v bigint[] NOT NULL, val text, part bigint)
        ON COMMIT DROP;
    EXECUTE format('INSERT INTO pg_temp.tgsis_mr_c (id, st, v)
                    SELECT v.%1$I, s.st, %2$s FROM %3$s v, (VALUES (1::smallint), (2), (4)) AS s (st)
                     WHERE %5$s AND v.%1$I = ANY ($5) AND %4$s', v_cellid, v_row, v_ckeyed, v_seen, v_cobj)
       USING p_geoid, v_base, v_parent.workingset, v_version.workingset, v_ckeys;
    IF v_runs THEN
        EXECUTE format('UPDATE pg_temp.tgsis_mr_c m SET part = v.part
                          FROM tgsis.part_ver v, (VALUES (1::smallint), (2), (4)) AS s (st)
                         WHERE v.geoid = $1 AND s.st = m.st AND m.id BETWEEN v.firstid AND v.lastid AND %s', v_seen)
           USING p_geoid, v_base, v_parent.workingset, v_version.workingset;
    END IF;
    IF v_ccanon IS NOT NULL THEN
        UPDATE pg_temp.tgsis_mr_c m SET val = r.val
          FROM tgsis.merge_property_rows(v_cpt, p_geoid, NULL, v_ckeys, v_base, v_parent.workingset, v_version.workingset, p_times, p_timem) AS r
         WHERE r.key = m.id AND r.seen & m.st <> 0;
        UPDATE pg_temp.tgsis_mr_c m SET val = v_cnull WHERE m.val IS NULL;
    END IF;
    ANALYZE pg_temp.tgsis_mr_v;
    ANALYZE pg_temp.tgsis_mr_c;

    -- 3. the version's new ids in the merged numbering (merge3's child renumbering): a new row with the
    -- content of a parent's new row takes its id (the k-th of equal contents the k-th), a new id the parent
    -- uses for something else a fresh one above every id of the three states, in ascending order (stored in
    -- chunks: the base's largest id is in its last chunk, the only one decoded)
    v_top := ARRAY[v_csrc, v_vsrc];
    FOR i IN 1 .. 2 LOOP
        IF p_times IS NULL AND tgsis.stored_in_chunks((ARRAY[v_table, 'vrtx'])[i]) THEN
            EXECUTE format('SELECT max(c.chunk) * (SELECT t.chunksize FROM tgsis.model_tables t WHERE t.tablename = %L)
                              FROM %s c WHERE c.geoid = $1 AND c.revision = ANY ($2) AND NOT (c.revclosed AND c.lastrevs && $2)',
                           (ARRAY[v_table, 'vrtx'])[i], tgsis.storage_table('tgsis', (ARRAY[v_table, 'vrtx'])[i]))
               INTO v_last USING p_geoid, v_base;
            v_top[i] := tgsis.storage_row_versions('tgsis', (ARRAY[v_table, 'vrtx'])[i], ARRAY[v_last]);
        END IF;
    END LOOP;
    EXECUTE format('SELECT greatest((SELECT max(m.id) FROM pg_temp.tgsis_mr_v m),
                                    (SELECT v.vrtxid FROM %3$s v WHERE %4$s AND v.revision = ANY ($2)
                                        AND NOT (v.revclosed AND v.lastrevs && $2) ORDER BY v.vrtxid DESC LIMIT 1)),
                           greatest((SELECT max(m.id) FROM pg_temp.tgsis_mr_c m),
                                    (SELECT v.%1$I FROM %2$s v WHERE %5$s AND v.revision = ANY ($2)
                                        AND NOT (v.revclosed AND v.lastrevs && $2) ORDER BY v.%1$I DESC LIMIT 1))',
                   v_cellid, v_top[1], v_top[2], v_obj, v_cobj)
       INTO v_top_v, v_top_c USING p_geoid, v_base;
    BEGIN  -- a fresh id above every id: none when the ids reach the top of bigint
        CREATE TEMPORARY TABLE tgsis_mr_vmap ON COMMIT DROP AS
        WITH pn AS (
            SELECT a.id, a.x, a.y, a.z, a.val, a.ref,
                   row_number() OVER (PARTITION BY a.x, a.y, a.z, a.val, a.ref ORDER BY a.id) AS rn
              FROM pg_temp.tgsis_mr_v a
             WHERE a.st = 2 AND NOT EXISTS (SELECT FROM pg_temp.tgsis_mr_v b WHERE b.id = a.id AND b.st = 1)),
        cn AS (
            SELECT a.id, a.x, a.y, a.z, a.val, a.ref,
                   row_number() OVER (PARTITION BY a.x, a.y, a.z, a.val, a.ref ORDER BY a.id) AS rn
              FROM pg_temp.tgsis_mr_v a
             WHERE a.st = 4 AND NOT EXISTS (SELECT FROM pg_temp.tgsis_mr_v b WHERE b.id = a.id AND b.st = 1)),
        matched AS (
            SELECT c.id AS old, p.id AS new
              FROM cn c JOIN pn p ON p.x = c.x AND p.y = c.y AND p.z = c.z AND p.val IS NOT DISTINCT FROM c.val
                                  AND p.ref IS NOT DISTINCT FROM c.ref AND p.rn = c.rn)
        SELECT m.old, m.new FROM matched m WHERE m.new <> m.old
        UNION ALL
        SELECT c.id, v_top_v + row_number() OVER (ORDER BY c.id)
          FROM cn c
         WHERE NOT EXISTS (SELECT FROM matched m WHERE m.old = c.id) AND EXISTS (SELECT FROM pn p WHERE p.id = c.id);
    EXCEPTION WHEN numeric_value_out_of_range THEN
        RAISE EXCEPTION 'feature % does not merge by region in version %: the version''s new vertices that clash with the parent''s need ids above %, and bigint ends at 9223372036854775807',
                p_geoid, quote_literal(p_version), v_top_v
            USING ERRCODE = 'TG100',
                  DETAIL = 'The merge by region gives the version''s new rows that clash with the parent''s a fresh id above every id of the three states.',
                  HINT = format('solve it as a whole object: SELECT tgsis.resolve_conflict(%L, ''feature'', %L, ''parent''|''child''|''manual'')',
                                p_version, p_geoid::text);
    END;
    IF EXISTS (SELECT FROM pg_temp.tgsis_mr_vmap) THEN
        UPDATE pg_temp.tgsis_mr_v m SET id = p.new FROM pg_temp.tgsis_mr_vmap p WHERE m.st = 4 AND m.id = p.old;
        UPDATE pg_temp.tgsis_mr_v m SET ref = p.new FROM pg_temp.tgsis_mr_vmap p WHERE m.st = 4 AND m.ref = p.old;
        UPDATE pg_temp.tgsis_mr_c m
           SET v = ARRAY(SELECT coalesce(p.new, u.x) FROM unnest(m.v) WITH ORDINALITY AS u(x, o)
                           LEFT JOIN pg_temp.tgsis_mr_vmap p ON p.old = u.x ORDER BY u.o)
         WHERE m.st = 4 AND m.v && (SELECT array_agg(p.old) FROM pg_temp.tgsis_mr_vmap p);
    END IF;
    BEGIN  -- a fresh id above every id: none when the ids reach the top of bigint
        CREATE TEMPORARY TABLE tgsis_mr_cmap ON COMMIT DROP AS
        WITH pn AS (
            SELECT a.id, tgsis.oriented_cell_key(a.v) AS k, a.val, a.part,
                   row_number() OVER (PARTITION BY tgsis.oriented_cell_key(a.v), a.val, a.part ORDER BY a.id) AS rn
              FROM pg_temp.tgsis_mr_c a
             WHERE a.st = 2 AND NOT EXISTS (SELECT FROM pg_temp.tgsis_mr_c b WHERE b.id = a.id AND b.st = 1)),
        cn AS (
            SELECT a.id, tgsis.oriented_cell_key(a.v) AS k, a.val, a.part,
                   row_number() OVER (PARTITION BY tgsis.oriented_cell_key(a.v), a.val, a.part ORDER BY a.id) AS rn
              FROM pg_temp.tgsis_mr_c a
             WHERE a.st = 4 AND NOT EXISTS (SELECT FROM pg_temp.tgsis_mr_c b WHERE b.id = a.id AND b.st = 1)),
        matched AS (
            SELECT c.id AS old, p.id AS new
              FROM cn c JOIN pn p ON p.k = c.k AND p.val IS NOT DISTINCT FROM c.val
                                  AND p.part IS NOT DISTINCT FROM c.part AND p.rn = c.rn)
        SELECT m.old, m.new FROM matched m WHERE m.new <> m.old
        UNION ALL
        SELECT c.id, v_top_c + row_number() OVER (ORDER BY c.id)
          FROM cn c
         WHERE NOT EXISTS (SELECT FROM matched m WHERE m.old = c.id) AND EXISTS (SELECT FROM pn p WHERE p.id = c.id);
    EXCEPTION WHEN numeric_value_out_of_range THEN
        RAISE EXCEPTION 'feature % does not merge by region in version %: the version''s new cells that clash with the parent''s need ids above %, and bigint ends at 9223372036854775807',
                p_geoid, quote_literal(p_version), v_top_c
            USING ERRCODE = 'TG100',
                  DETAIL = 'The merge by region gives the version''s new rows that clash with the parent''s a fresh id above every id of the three states.',
                  HINT = format('solve it as a whole object: SELECT tgsis.resolve_conflict(%L, ''feature'', %L, ''parent''|''child''|''manual'')',
                                p_version, p_geoid::text);
    END;
    UPDATE pg_temp.tgsis_mr_c m SET id = p.new FROM pg_temp.tgsis_mr_cmap p WHERE m.st = 4 AND m.id = p.old;

    -- 4. each side's edit against the base, per id (merged numbering)
    CREATE TEMPORARY TABLE tgsis_mr_vx ON COMMIT DROP AS
    SELECT w.*,
           coalesce(w.ib AND w.ip AND (w.bx, w.by, w.bz) <> (w.px, w.py, w.pz), false) AS p_moved,
           coalesce(w.ib AND w.ic AND (w.bx, w.by, w.bz) <> (w.cx, w.cy, w.cz), false) AS c_moved,
           w.ib <> w.ip OR coalesce(w.ib AND w.ip AND (w.bx, w.by, w.bz) <> (w.px, w.py, w.pz), false) AS p_shape,
           w.ib <> w.ic OR coalesce(w.ib AND w.ic AND (w.bx, w.by, w.bz) <> (w.cx, w.cy, w.cz), false) AS c_shape,
           w.ib <> w.ip OR coalesce(w.ib AND w.ip AND ((w.bx, w.by, w.bz) <> (w.px, w.py, w.pz)
                                                     OR w.bval IS DISTINCT FROM w.pval OR w.bref IS DISTINCT FROM w.pref), false)
               AS p_changed,
           w.ib <> w.ic OR coalesce(w.ib AND w.ic AND ((w.bx, w.by, w.bz) <> (w.cx, w.cy, w.cz)
                                                     OR w.bval IS DISTINCT FROM w.cval OR w.bref IS DISTINCT FROM w.cref), false)
               AS c_changed,
           w.ip <> w.ic OR coalesce(w.ip AND w.ic AND ((w.px, w.py, w.pz) <> (w.cx, w.cy, w.cz)
                                                     OR w.pval IS DISTINCT FROM w.cval OR w.pref IS DISTINCT FROM w.cref), false)
               AS differ
      FROM (SELECT m.id, bool_or(m.st = 1) AS ib, bool_or(m.st = 2) AS ip, bool_or(m.st = 4) AS ic,
                   min(m.x) FILTER (WHERE m.st = 1) AS bx, min(m.y) FILTER (WHERE m.st = 1) AS by,
                   min(m.z) FILTER (WHERE m.st = 1) AS bz, min(m.x) FILTER (WHERE m.st = 2) AS px,
                   min(m.y) FILTER (WHERE m.st = 2) AS py, min(m.z) FILTER (WHERE m.st = 2) AS pz,
                   min(m.x) FILTER (WHERE m.st = 4) AS cx, min(m.y) FILTER (WHERE m.st = 4) AS cy,
                   min(m.z) FILTER (WHERE m.st = 4) AS cz,
                   min(m.val) FILTER (WHERE m.st = 1) AS bval, min(m.val) FILTER (WHERE m.st = 2) AS pval,
                   min(m.val) FILTER (WHERE m.st = 4) AS cval,
                   min(m.ref) FILTER (WHERE m.st = 1) AS bref, min(m.ref) FILTER (WHERE m.st = 2) AS pref,
                   min(m.ref) FILTER (WHERE m.st = 4) AS cref
              FROM pg_temp.tgsis_mr_v m GROUP BY m.id) AS w;
    CREATE TEMPORARY TABLE tgsis_mr_cx ON COMMIT DROP AS
    SELECT w.*,
           w.ib <> w.ip OR coalesce(w.ib AND w.ip AND w.bv <> w.pv AND w.bk <> w.pk, false) AS p_topo,
           w.ib <> w.ic OR coalesce(w.ib AND w.ic AND w.bv <> w.cv AND w.bk <> w.ck, false) AS c_topo,
           w.ib <> w.ip OR coalesce(w.ib AND w.ip AND ((w.bv <> w.pv AND w.bk <> w.pk)
                                                     OR w.bval IS DISTINCT FROM w.pval OR w.bpart IS DISTINCT FROM w.ppart), false)
               AS p_changed,
           w.ib <> w.ic OR coalesce(w.ib AND w.ic AND ((w.bv <> w.cv AND w.bk <> w.ck)
                                                     OR w.bval IS DISTINCT FROM w.cval OR w.bpart IS DISTINCT FROM w.cpart), false)
               AS c_changed,
           w.ip <> w.ic OR coalesce(w.ip AND w.ic AND ((w.pv <> w.cv AND w.pk <> w.ck)
                                                     OR w.pval IS DISTINCT FROM w.cval OR w.ppart IS DISTINCT FROM w.cpart), false)
               AS differ
      FROM (SELECT u.*, tgsis.oriented_cell_key(u.bv) AS bk, tgsis.oriented_cell_key(u.pv) AS pk,
                   tgsis.oriented_cell_key(u.cv) AS ck
              FROM (SELECT m.id, bool_or(m.st = 1) AS ib, bool_or(m.st = 2) AS ip, bool_or(m.st = 4) AS ic,
                           min(m.v) FILTER (WHERE m.st = 1) AS bv, min(m.v) FILTER (WHERE m.st = 2) AS pv,
                           min(m.v) FILTER (WHERE m.st = 4) AS cv,
                           min(m.val) FILTER (WHERE m.st = 1) AS bval, min(m.val) FILTER (WHERE m.st = 2) AS pval,
                           min(m.val) FILTER (WHERE m.st = 4) AS cval,
                           min(m.part) FILTER (WHERE m.st = 1) AS bpart, min(m.part) FILTER (WHERE m.st = 2) AS ppart,
                           min(m.part) FILTER (WHERE m.st = 4) AS cpart
                      FROM pg_temp.tgsis_mr_c m GROUP BY m.id) AS u) AS w;

    -- 5. the one-ring margin: the base's cells on a vertex either side moved, added or removed. Found through
    -- the vertex BRIN of the cell storage by spans of those ids (stored in chunks: the chunks whose vertex-id
    -- bounds hold one of them, tgsis.storage_cells_on), each cell tested exactly against a hashed
    -- set of them (tgsis.cells_on_vertices_sql), and meeting the changes of its corners by equality
    CREATE TEMPORARY TABLE tgsis_mr_margin (id bigint NOT NULL, v bigint[] NOT NULL, sides integer NOT NULL) ON COMMIT DROP;
    v_shape := ARRAY(SELECT x.id FROM pg_temp.tgsis_mr_vx x WHERE x.p_shape OR x.c_shape ORDER BY x.id);
    IF cardinality(v_shape) > 0 THEN
        -- (the cells first, MATERIALIZED: planned with the GROUP BY, the primary key's order by cell id made
        -- PostgreSQL 15 read every cell of the object through it rather than the BRIN's few ranges)
        EXECUTE format('WITH c AS MATERIALIZED (
                            SELECT v.%1$I AS id, %2$s AS v FROM %3$s v
                             WHERE %5$s AND v.revision = ANY ($2) AND NOT (v.revclosed AND v.lastrevs && $2)
                               AND %4$s)
                        INSERT INTO pg_temp.tgsis_mr_margin (id, v, sides)
                        SELECT c.id, c.v, bit_or(x.p_shape::integer | (x.c_shape::integer << 1))
                          FROM c
                          CROSS JOIN LATERAL unnest(c.v) AS u (vid)
                          JOIN pg_temp.tgsis_mr_vx x ON x.id = u.vid AND (x.p_shape OR x.c_shape)
                         GROUP BY c.id, c.v',
                       v_cellid, v_row,
                       -- (model 1 stored in chunks: only the chunks whose vertex-id bounds hold one of those vertices)
                       CASE WHEN p_times IS NULL THEN tgsis.storage_cells_on(v_table, v_shape) ELSE v_csrc END,
                       tgsis.cells_on_vertices_sql(v_k, v_shape, '$3'), v_cobj)
           USING p_geoid, v_base, v_shape;
    END IF;

    -- 6. each side's footprint (side 1 parent, 2 version): its changed cells and margin; its changed vertices
    -- and the vertices of the cells it added, removed or reconnected (base's row and its own)
    CREATE TEMPORARY TABLE tgsis_mr_fc ON COMMIT DROP AS
    SELECT x.id, 1 AS side FROM pg_temp.tgsis_mr_cx x WHERE x.p_changed
    UNION SELECT x.id, 2 FROM pg_temp.tgsis_mr_cx x WHERE x.c_changed
    UNION SELECT g.id, 1 FROM pg_temp.tgsis_mr_margin g WHERE g.sides & 1 <> 0
    UNION SELECT g.id, 2 FROM pg_temp.tgsis_mr_margin g WHERE g.sides & 2 <> 0;
    CREATE TEMPORARY TABLE tgsis_mr_fv ON COMMIT DROP AS
    SELECT x.id, 1 AS side FROM pg_temp.tgsis_mr_vx x WHERE x.p_changed
    UNION SELECT x.id, 2 FROM pg_temp.tgsis_mr_vx x WHERE x.c_changed
    UNION SELECT unnest(x.bv || x.pv), 1 FROM pg_temp.tgsis_mr_cx x WHERE x.p_topo
    UNION SELECT unnest(x.bv || x.cv), 2 FROM pg_temp.tgsis_mr_cx x WHERE x.c_topo;

    -- 7. the regions: connected components of the footprints' elements, a cell joined to a vertex of its
    -- row (base's or the side's) when both are in one side's footprint; nodes numbered as merge3 numbers
    -- them (vertices ascending, then cells ascending), each labelled by the least node of its component
    CREATE TEMPORARY TABLE tgsis_mr_node ON COMMIT DROP AS
    SELECT (row_number() OVER (ORDER BY n.kind DESC, n.id) - 1)::integer AS node, n.kind, n.id,
           (row_number() OVER (ORDER BY n.kind DESC, n.id) - 1)::integer AS label
      FROM (SELECT DISTINCT f.id, 'v'::text AS kind FROM pg_temp.tgsis_mr_fv f
            UNION ALL SELECT DISTINCT f.id, 'c' FROM pg_temp.tgsis_mr_fc f) AS n;
    IF NOT EXISTS (SELECT FROM pg_temp.tgsis_mr_node) THEN  -- no region
        RETURN 0;
    END IF;
    CREATE TEMPORARY TABLE tgsis_mr_edge ON COMMIT DROP AS
    WITH rows AS (
        SELECT f.id, f.side, CASE WHEN x.id IS NULL THEN g.v ELSE x.bv END AS brow,
               CASE WHEN x.id IS NULL THEN g.v WHEN f.side = 1 THEN x.pv ELSE x.cv END AS srow
          FROM pg_temp.tgsis_mr_fc f
          LEFT JOIN pg_temp.tgsis_mr_cx x ON x.id = f.id
          LEFT JOIN pg_temp.tgsis_mr_margin g ON g.id = f.id),
    pairs AS (
        SELECT DISTINCT r.id AS cell, u.vid
          FROM rows r CROSS JOIN LATERAL unnest(r.brow || r.srow) AS u(vid)
          JOIN pg_temp.tgsis_mr_fv fv ON fv.id = u.vid AND fv.side = r.side)
    SELECT c.node AS a, v.node AS b
      FROM pairs p JOIN pg_temp.tgsis_mr_node c ON c.kind = 'c' AND c.id = p.cell
      JOIN pg_temp.tgsis_mr_node v ON v.kind = 'v' AND v.id = p.vid
    UNION ALL
    SELECT v.node, c.node
      FROM pairs p JOIN pg_temp.tgsis_mr_node c ON c.kind = 'c' AND c.id = p.cell
      JOIN pg_temp.tgsis_mr_node v ON v.kind = 'v' AND v.id = p.vid;
    CREATE INDEX ON pg_temp.tgsis_mr_edge (a);
    CREATE UNIQUE INDEX ON pg_temp.tgsis_mr_node (node);
    ANALYZE pg_temp.tgsis_mr_node;
    ANALYZE pg_temp.tgsis_mr_edge;
    -- the components by union-find over the node numbers in arrays (v_up[node + 1]: the node's parent, never
    -- above the node; a union hangs the larger root under the smaller, a find halves its path), so that
    -- each root is the least node of its component: one pass over the edges, then one over the nodes in
    -- ascending order (a node's parent is already its root)
    v_up := ARRAY(SELECT n.node FROM pg_temp.tgsis_mr_node n ORDER BY n.node);
    SELECT coalesce(array_agg(e.a), '{}'), coalesce(array_agg(e.b), '{}') INTO v_ea, v_eb
      FROM pg_temp.tgsis_mr_edge e WHERE e.a < e.b;
    FOR i IN 1 .. cardinality(v_ea) LOOP
        v_x := v_ea[i];
        WHILE v_up[v_x + 1] <> v_x LOOP
            v_up[v_x + 1] := v_up[v_up[v_x + 1] + 1];
            v_x := v_up[v_x + 1];
        END LOOP;
        v_y := v_eb[i];
        WHILE v_up[v_y + 1] <> v_y LOOP
            v_up[v_y + 1] := v_up[v_up[v_y + 1] + 1];
            v_y := v_up[v_y + 1];
        END LOOP;
        IF v_x < v_y THEN
            v_up[v_y + 1] := v_x;
        ELSIF v_y < v_x THEN
            v_up[v_x + 1] := v_y;
        END IF;
    END LOOP;
    FOR i IN 1 .. cardinality(v_up) LOOP
        v_up[i] := v_up[v_up[i] + 1];
    END LOOP;
    UPDATE pg_temp.tgsis_mr_node w SET label = u.label
      FROM unnest(v_up) WITH ORDINALITY AS u (label, o)
     WHERE w.node = u.o - 1 AND u.label <> w.label;

    -- 8. the base's coordinates of the vertices no side changed that a region touches (corners of its cells),
    -- for the boxes of the regions
    CREATE TEMPORARY TABLE tgsis_mr_vb (id bigint, x float8, y float8, z float8) ON COMMIT DROP;
    v_ids := ARRAY(SELECT n.id FROM pg_temp.tgsis_mr_node n WHERE n.kind = 'v'
                   UNION SELECT unnest(g.v) FROM pg_temp.tgsis_mr_margin g
                   UNION SELECT unnest(c.v) FROM pg_temp.tgsis_mr_c c
                   EXCEPT SELECT m.id FROM pg_temp.tgsis_mr_v m);
    EXECUTE format('INSERT INTO pg_temp.tgsis_mr_vb
             SELECT v.vrtxid, v.x, v.y, v.z FROM %s v
              WHERE %s AND v.revision = ANY ($2) AND NOT (v.revclosed AND v.lastrevs && $2) AND v.vrtxid = ANY ($3)',
                   CASE WHEN p_times IS NULL THEN tgsis.storage_row_versions('tgsis', 'vrtx', v_ids) ELSE v_vsrc END, v_obj)
       USING p_geoid, v_base, v_ids;
    RETURN (SELECT count(*) FROM pg_temp.tgsis_mr_node);
END
$$;

COMMENT ON FUNCTION tgsis.mesh_merge_work(text, bigint, float8, float8) IS
    'the work tables (pg_temp.tgsis_mr_*, left to the caller) of the three-way merge by region of a model-1 feature changed both in a version and in its parent: rows per state, renumbering, edits, footprints, region labels; with p_times, of that instant of a model-2 feature (its times_vrtx / times_trgl rows and property rows keyed (_times, _idx)); with p_timem too, of that geometry instant of that period of a model-3 feature (d4dvrtx, d4dtrgl, property rows keyed (_timem, _timet, _idx)); returns the number of footprint elements; TG300 / TG100 for a feature not changed on both sides / that does not merge by region, 42501 for a class the role may not read';

-- internal to the merges, not executable by PUBLIC (tests/test_function_grants.py); tgsis.mesh_merge_regions, which a tgsis role calls as itself, runs it
REVOKE ALL ON FUNCTION tgsis.mesh_merge_work(text, bigint, float8, float8) FROM PUBLIC;
GRANT EXECUTE ON FUNCTION tgsis.mesh_merge_work(text, bigint, float8, float8) TO tgsis_reader;
