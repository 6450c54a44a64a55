-- tgsis.slice_only_edits(version, geoid, side): the slices of a model-2/3 feature only one side changed, or NULL.
-- A surface at instants (model 2) merges instant by instant and an evolving
-- surface (model 3) geometry instant by geometry instant of each topology
-- period (docs/merge.md, "Models 2 and 3"): a slice (an instant; a geometry
-- instant with its period's nodes and triangles) that only one side changed
-- (moved, added, removed, its property rows) merges by itself. Their regions
-- are found by the Python client only, so a psql user's whole-object
-- tgsis.resolve_conflict(..., 'parent' | 'child') would drop those edits of
-- the other side with nobody having looked; resolve_conflict asks this
-- function first. Each side's rows of each slice are compared as text
-- (floats exactly, -0 as 0) over every table of the object's state: the
-- model tables of the time model and the class's property tables (keyed by
-- the time key), read from the storage at the three revision sets (base: the
-- version at its initrevision; parent and version: their working sets), the
-- class tables through tgsis.storage_run. NULL also when the object does not
-- merge by region slice by slice (an object-level conflict: a slice removed
-- on one side and changed on the other, added on both sides differently, a
-- per-instant feature property set on both sides to other values, a
-- model-3 period's topology changed on both sides differently, a geometry
-- instant added on one side to a period whose topology the other changed:
-- TG308): there the whole-object solution is the way, as the Python merge's
-- refusal says.
-- A role that may not read the feature's class is refused (42501), as
-- tgsis.mesh_merge_regions refuses it: the slices' instants are the class's
-- data, and tgsis.resolve_conflict (SECURITY DEFINER, reading as tgsis's
-- owner) would otherwise name them in its message.
-- p_side: 'parent' or 'child' (the side whose edits a solution would drop).
CREATE FUNCTION tgsis.slice_only_edits(p_version text, p_geoid bigint, p_side text)
RETURNS text
LANGUAGE plpgsql
VOLATILE
SET search_path = pg_catalog, pg_temp
SET extra_float_digits = 1
AS $$
DECLARE
    v_version tgsis.versions;
    v_parent  tgsis.versions;
    v_base    integer[];
    v_class   tgsis.catalog;
    v_evolve  boolean;
    v_t       tgsis.versioned_tables;
    v_tables  text[][];
    v_spec    text[];
    v_cols    text;
    v_km      text;
    v_kt      text;
    v_rows    text[] := '{}';
    v_part    text[];
    v_result  text;
BEGIN
    IF p_side NOT IN ('parent', 'child') THEN
        RAISE EXCEPTION 'side % is not parent or child', quote_literal(p_side) USING ERRCODE = 'TG100';
    END IF;
    SELECT * INTO v_version FROM tgsis.versions WHERE versionid = tgsis.version_id(p_version);
    IF v_version.parentid IS NULL THEN
        RETURN NULL;
    END IF;
    SELECT * INTO v_parent FROM tgsis.versions WHERE versionid = v_version.parentid;
    SELECT * INTO v_class FROM tgsis.catalog WHERE classname = tgsis.class_of_geoid(p_geoid);
    IF NOT FOUND OR v_class.timemodel NOT IN ('INSTANTS', 'EVOLVING') THEN
        RETURN NULL;
    END IF;
    IF p_geoid IN (SELECT tgsis.class_denied_geoids('SELECT')) THEN
        RAISE EXCEPTION 'role % may not read feature % (its class): the slices only one side changed cannot be told',
                quote_ident(tgsis.calling_role()), p_geoid
            USING ERRCODE = '42501',
                  HINT = 'a role that may read the class can do it, or the class''s owner lets this role read it (in psql: GRANT SELECT ON its feature table)';
    END IF;
    v_evolve := v_class.timemodel = 'EVOLVING';
    v_base := tgsis.revision_set(v_version.versionid, v_version.initrevision);
    -- (schema, table, object key column, period key column, instant key column or '')
    IF v_evolve THEN
        v_tables := ARRAY[['tgsis', 'timem', 'geoid', 'timem', ''], ['tgsis', 'timet', 'geoid', 'timem', 'timet'],
                          ['tgsis', 'node', 'geoid', 'timem', ''], ['tgsis', 'd4dtrgl', 'geoid', 'timem', ''],
                          ['tgsis', 'd4dvrtx', 'geoid', 'timem', 'timet']];
    ELSE
        v_tables := ARRAY[['tgsis', 'times', 'geoid', 'times', ''], ['tgsis', 'times_vrtx', 'geoid', 'times', ''],
                          ['tgsis', 'times_trgl', 'geoid', 'times', '']];
    END IF;
    FOR v_t IN
        SELECT t.* FROM tgsis.versioned_tables t
         WHERE t.schemaname = v_class.schemaname
           AND t.tablename IN (v_class.cellprotable, v_class.otherprotable, v_class.protablename)
    LOOP
        v_tables := v_tables || ARRAY[[v_t.schemaname, v_t.tablename, '_geoid',
                                       CASE WHEN v_evolve THEN '_timem' ELSE '_times' END,
                                       CASE WHEN v_evolve THEN '_timet' ELSE '' END]];
    END LOOP;
    -- per table, side and slice key: one digest of the rows as text; 1 base, 2 parent, 3 version
    FOR i IN 1 .. array_length(v_tables, 1) LOOP
        v_spec := ARRAY(SELECT unnest(v_tables[i:i][1:5]));
        SELECT * INTO v_t FROM tgsis.versioned_tables t WHERE t.schemaname = v_spec[1] AND t.tablename = v_spec[2];
        IF NOT FOUND THEN
            CONTINUE;  -- not versioned: the same rows on every side
        END IF;
        SELECT string_agg(format('v.%I', a.attname), ', ' ORDER BY a.attnum) INTO v_cols
          FROM pg_catalog.pg_attribute a
         WHERE a.attrelid = pg_catalog.to_regclass(format('%I.%I', v_spec[1], v_spec[2]))
           AND a.attnum > 0 AND NOT a.attisdropped;
        v_km := format('(v.%I + 0)::text', v_spec[4]);
        v_kt := CASE WHEN v_spec[5] = '' THEN 'NULL::text' ELSE format('(v.%I + 0)::text', v_spec[5]) END;
        SELECT v_rows || coalesce(array_agg(r[1] || E'\x1f' || coalesce(r[2], '') || E'\x1f' || coalesce(r[3], '')
                                            || E'\x1f' || v_spec[2] || E'\x1f' || r[4]), '{}')
          INTO v_rows
          FROM tgsis.storage_run(v_t, false, format(
                 'SELECT ARRAY[s.side::text, %1$s, %2$s, md5(string_agg(ROW(%3$s)::text, E''\n'' ORDER BY ROW(%3$s)::text))]
                    FROM (VALUES (1, $2), (2, $5::integer[]), (3, $3)) AS s (side, revs)
                    JOIN %4$s%5$s v ON v.%6$I = $1[1]::bigint
                                    AND v.revision = ANY (s.revs) AND NOT (v.revclosed AND v.lastrevs && s.revs)
                   GROUP BY s.side, %1$s, %2$s',
                 v_km, v_kt, v_cols, tgsis.storage_row_versions(v_spec[1], v_spec[2]), '', v_spec[3]),
               p_1 => ARRAY[p_geoid::text], p_2 => v_base, p_3 => v_version.workingset,
               p_5 => v_parent.workingset::bigint[]) AS r;
        IF v_spec[2] = v_class.protablename THEN  -- per-instant feature properties: column by column, as Python merges them
            SELECT string_agg(format('(%L, quote_nullable(v.%I::text))', a.attname, a.attname), ', ' ORDER BY a.attnum)
              INTO v_cols
              FROM pg_catalog.pg_attribute a
             WHERE a.attrelid = pg_catalog.to_regclass(format('%I.%I', v_spec[1], v_spec[2]))
               AND a.attnum > 0 AND NOT a.attisdropped AND a.attname NOT IN ('_geoid', '_times', '_timem', '_timet');
            CONTINUE WHEN v_cols IS NULL;
            SELECT v_rows || coalesce(array_agg(r[1] || E'\x1f' || coalesce(r[2], '') || E'\x1f' || coalesce(r[3], '')
                                                || E'\x1f' || 'pros:' || r[4] || E'\x1f' || r[5]), '{}')
              INTO v_rows
              FROM tgsis.storage_run(v_t, false, format(
                     'SELECT ARRAY[s.side::text, %1$s, %2$s, c.name, c.value]
                        FROM (VALUES (1, $2), (2, $5::integer[]), (3, $3)) AS s (side, revs)
                        JOIN %4$s%5$s v ON v.%6$I = $1[1]::bigint
                                        AND v.revision = ANY (s.revs) AND NOT (v.revclosed AND v.lastrevs && s.revs)
                       CROSS JOIN LATERAL (VALUES %3$s) AS c (name, value)',
                     v_km, v_kt, v_cols, tgsis.storage_row_versions(v_spec[1], v_spec[2]), '', v_spec[3]),
                   p_1 => ARRAY[p_geoid::text], p_2 => v_base, p_3 => v_version.workingset,
                   p_5 => v_parent.workingset::bigint[]) AS r;
        END IF;
    END LOOP;
    WITH e AS (  -- (side, period key, instant key or '', table, digest)
        SELECT p[1]::integer AS side, p[2] AS km, p[3] AS kt, p[4] AS tab, p[5] AS digest
          FROM unnest(v_rows) AS x (line), LATERAL (SELECT string_to_array(x.line, E'\x1f') AS p) q
    ), slices AS (  -- the slices of any side: the instants (model 3: the geometry instants)
        SELECT DISTINCT km, kt FROM e WHERE tab = CASE WHEN v_evolve THEN 'timet' ELSE 'times' END
    ), per_side AS (  -- a slice's digest on a side: NULL when the side has no such slice
        SELECT s.km, s.kt, d.side,
               CASE WHEN bool_or(e.tab = CASE WHEN v_evolve THEN 'timet' ELSE 'times' END)
                    THEN md5(string_agg(e.tab || ':' || e.digest, ',' ORDER BY e.tab, e.kt)) END AS digest
          FROM slices s CROSS JOIN (VALUES (1), (2), (3)) AS d (side)
          LEFT JOIN e ON e.side = d.side AND e.km = s.km AND (e.kt = s.kt OR e.kt = '')
         GROUP BY s.km, s.kt, d.side
    ), sides AS (
        SELECT km, kt,
               max(digest) FILTER (WHERE side = 1) AS b,
               max(digest) FILTER (WHERE side = 2) AS p,
               max(digest) FILTER (WHERE side = 3) AS c
          FROM per_side GROUP BY km, kt
    ), topology AS (  -- model 3: a period's nodes and triangles per side
        SELECT km,
               md5(string_agg(tab || ':' || digest, ',' ORDER BY tab) FILTER (WHERE side = 1)) AS b,
               md5(string_agg(tab || ':' || digest, ',' ORDER BY tab) FILTER (WHERE side = 2)) AS p,
               md5(string_agg(tab || ':' || digest, ',' ORDER BY tab) FILTER (WHERE side = 3)) AS c
          FROM e WHERE tab IN ('node', 'd4dtrgl') GROUP BY km
    )
    SELECT CASE
             WHEN EXISTS (SELECT FROM sides s  -- object-level conflicts: solved as a whole object
                           WHERE s.p IS DISTINCT FROM s.b AND s.c IS DISTINCT FROM s.b AND s.p IS DISTINCT FROM s.c
                             AND (s.b IS NULL OR s.p IS NULL OR s.c IS NULL))
               OR EXISTS (SELECT FROM topology t
                           WHERE t.p IS DISTINCT FROM t.b AND t.c IS DISTINCT FROM t.b AND t.p IS DISTINCT FROM t.c)
               -- a per-instant feature property both sides set to other values (removed against changed too)
               OR EXISTS (SELECT FROM (SELECT max(digest) FILTER (WHERE side = 1) AS b,
                                              max(digest) FILTER (WHERE side = 2) AS p,
                                              max(digest) FILTER (WHERE side = 3) AS c
                                         FROM e WHERE tab LIKE 'pros:%' GROUP BY km, kt, tab) x
                           WHERE x.p IS DISTINCT FROM x.b AND x.c IS DISTINCT FROM x.b AND x.p IS DISTINCT FROM x.c)
               -- a geometry instant added to a period whose topology the other side changed (TG308 in Python)
               OR EXISTS (SELECT FROM topology t JOIN sides s ON s.km = t.km
                           WHERE t.b IS NOT NULL AND s.b IS NULL
                             AND ((t.p IS DISTINCT FROM t.b AND s.c IS NOT NULL AND s.p IS NULL)
                               OR (t.c IS DISTINCT FROM t.b AND s.p IS NOT NULL AND s.c IS NULL)))
             THEN NULL
             ELSE (SELECT string_agg(CASE WHEN v_evolve
                                          THEN format('geometry instant %s of the period starting at %s', s.kt, s.km)
                                          ELSE format('instant %s', s.km) END, ', '
                                     ORDER BY s.km::float8, nullif(s.kt, '')::float8)
                     FROM sides s
                    WHERE CASE p_side WHEN 'parent' THEN s.p IS DISTINCT FROM s.b AND s.c IS NOT DISTINCT FROM s.b
                                      ELSE s.c IS DISTINCT FROM s.b AND s.p IS NOT DISTINCT FROM s.b END)
           END
      INTO v_result;
    RETURN v_result;
END
$$;

COMMENT ON FUNCTION tgsis.slice_only_edits(text, bigint, text) IS
    'the slices (instants; geometry instants of topology periods) of a model-2/3 feature that only the given side (parent or child) changed since the version''s base, as text, or NULL (none, not model 2/3, or an object-level conflict): what a whole-object solution taking the other side would drop although it merges by itself; 42501 for a role that may not read the feature''s class';

-- internal to the merges, not executable by PUBLIC (tests/test_function_grants.py); a tgsis role may ask it as itself (docs/versioning.md)
REVOKE ALL ON FUNCTION tgsis.slice_only_edits(text, bigint, text) FROM PUBLIC;
GRANT EXECUTE ON FUNCTION tgsis.slice_only_edits(text, bigint, text) TO tgsis_reader;
