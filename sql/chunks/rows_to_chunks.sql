-- tgsis.rows_to_chunks(table): fill the empty tgsis.<table>_chunk from the rows of the row storage, losslessly, every set keeping what it sees.
-- The conversion the storage switch and the upgrade call (docs/storage.md,
-- "Upgrading an existing database, and back"); it does not drop the rows (the
-- switch decides). Set-based, one INSERT ... SELECT:
-- - unversioned storage: the rows grouped by (key, id >> log2(chunksize)) into
--   arrays with holes, revision 0;
-- - versioned storage: per chunk, its event revisions E (those in which one of
--   its rows was written, revision, or closed, lastrevs); each W of E has a set:
--   its stored set (tgsis.revisions.visibleset), or the working set of the
--   version it is the working revision of, or, for a number compress_versions
--   dropped from tgsis.revisions but left on rows as a label, the part up to W
--   of the first set holding it (a set's revisions up to one of them are that
--   one's set: sets are chains of ancestors' revisions); a W no set holds
--   hides nothing and shows nothing, and is left out. The chunk's content as
--   W's set sees it (revision in the set, lastrevs meeting none of it) is the
--   chunk version (revision W, content) unless empty, closed in the
--   revisions W' of E (W' <> W) whose set holds W: every set then sees one
--   chunk version per chunk, the one of its largest event revision, holding
--   exactly the rows it saw.
-- Then the chunk table is analyzed (its statistics plan the proof and the
-- reads after the switch) and tgsis.check_chunk_conversion proves it for every working set and every
-- revision's set (TG000 otherwise: the caller's transaction changes nothing).
-- The row storage is locked against writes (SHARE), and the version rows
-- (FOR SHARE: no new revision, merge or compress meanwhile). Refused: a chunk
-- table that holds chunks already (TG201), no chunk table or view (TG200).
-- Returns the number of chunk versions written. Internal: the caller's rights.
-- The table is one of tgsis.chunk_registry: a model table, or a class's
-- property table ('schema.table'), whose NULL values stay NULL in their slot
-- (holes alone marks the absent ids); a vector property's chunk array is
-- two-dimensional (slots x k), a NULL vector's row and a hole's k NULLs;
-- a point's (a G-map's vertex) two-dimensional (slots x m), a hole's row m NULLs.
CREATE FUNCTION tgsis.rows_to_chunks(p_table text)
RETURNS bigint
LANGUAGE plpgsql
VOLATILE
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_reg       record;
    v_chunk     regclass;
    v_storage   regclass;
    v_shift     integer;
    v_size      bigint;
    v_cc        text;
    v_keys      text[];
    v_floats    text[];
    v_refs      text[];
    v_vals      text[];
    v_k         text[];    -- the chunk key's columns (quoted): the keys, then chunk
    v_versioned boolean;
    v_parts     jsonb;
    v_part      record;
    v_sql       text;
    v_n         bigint;
    v_any       boolean;
BEGIN
    v_chunk := tgsis.chunk_table_of(p_table, true);  -- TG200 / TG100
    SELECT * INTO v_reg FROM tgsis.chunk_registry(p_table) r;
    v_storage := tgsis.storage_table(v_reg.schemaname, v_reg.tablename)::regclass;
    v_versioned := EXISTS (SELECT FROM tgsis.versioned_tables t WHERE t.schemaname = v_reg.schemaname AND t.tablename = v_reg.tablename);
    IF v_versioned THEN
        PERFORM FROM tgsis.versions v ORDER BY v.versionid FOR SHARE;
    END IF;
    EXECUTE format('LOCK TABLE %s IN SHARE MODE', v_storage);
    EXECUTE format('LOCK TABLE %s IN SHARE ROW EXCLUSIVE MODE', v_chunk);
    EXECUTE format('SELECT EXISTS (SELECT FROM %s)', v_chunk) INTO STRICT v_any;
    IF v_any THEN
        RAISE EXCEPTION '% holds chunks already', v_chunk
            USING ERRCODE = 'TG201',
                  DETAIL = format('Rows are converted into an empty chunk table only; %s is not.', v_chunk),
                  HINT = 'convert into a new, empty chunk table';
    END IF;

    v_size := v_reg.chunksize;
    v_shift := round(log(2, v_reg.chunksize))::integer;
    v_cc := v_reg.chunkcolumn;
    v_keys := tgsis.chunk_key(p_table);
    -- the arrays of values (coordinates, or a class's properties), built alike
    v_floats := ARRAY(SELECT c.name FROM tgsis.chunk_columns(p_table) c WHERE c.role IN ('float', 'value') ORDER BY c.colorder);
    v_refs := ARRAY(SELECT c.name FROM tgsis.chunk_columns(p_table) c WHERE c.role = 'ref' ORDER BY c.colorder);
    v_vals := ARRAY(SELECT c.name FROM tgsis.chunk_columns(p_table) c WHERE c.role IN ('float', 'ref', 'value', 'vector', 'point')
                     ORDER BY c.colorder);
    v_k := ARRAY(SELECT quote_ident(k) FROM unnest(v_keys) AS k) || 'chunk'::text;
    v_parts := jsonb_build_object(
        'storage', v_storage::text,
        'chunk', v_chunk::text,
        'rk_as', array_to_string(ARRAY(SELECT format('r.%I AS %I', k, k) FROM unnest(v_keys) AS k)
                                 || format('r.%I >> %s AS chunk', v_cc, v_shift), ', '),
        -- the event revisions of each chunk, each with its set (unversioned: revision 0, every row)
        'events', CASE WHEN v_versioned THEN
            'SELECT DISTINCT {rk_as}, e.w FROM {storage} r CROSS JOIN LATERAL unnest(r.revision || r.lastrevs) AS e(w)'
            ELSE 'SELECT DISTINCT {rk_as}, 0 AS w FROM {storage} r' END,
        'wsets', CASE WHEN v_versioned THEN
            $w$SELECT ws.w, z.revs FROM (SELECT DISTINCT ev0.w FROM ev0) ws CROSS JOIN LATERAL (SELECT coalesce(
                (SELECT x.visibleset FROM tgsis.revisions x WHERE x.revision = ws.w AND x.visibleset IS NOT NULL),
                (SELECT v.workingset FROM tgsis.versions v WHERE v.workingrevision = ws.w),
                (SELECT ARRAY(SELECT u.r FROM unnest(s.revs) AS u(r) WHERE u.r <= ws.w ORDER BY u.r)
                   FROM sets s WHERE ws.w = ANY (s.revs) ORDER BY s.ord LIMIT 1)) AS revs) z
             WHERE z.revs IS NOT NULL$w$
            ELSE 'SELECT 0 AS w, NULL::integer[] AS revs' END,
        'vis', CASE WHEN v_versioned THEN 'r.revision = ANY (e.revs) AND NOT (r.lastrevs && e.revs)' ELSE 'true' END,
        'K', array_to_string(v_k, ', '),
        'e_K', array_to_string(ARRAY(SELECT 'e.' || k FROM unnest(v_k) AS k), ', '),
        'n_K', array_to_string(ARRAY(SELECT 'n.' || k FROM unnest(v_k) AS k), ', '),
        'm_K', array_to_string(ARRAY(SELECT 'm.' || k FROM unnest(v_k) AS k), ', '),
        'match_e_f', array_to_string(ARRAY(SELECT format('f.%s = e.%s', k, k) FROM unnest(v_k) AS k), ' AND '),
        'match_m_e', array_to_string(ARRAY(SELECT format('m.%s = e.%s', k, k) FROM unnest(v_k) AS k), ' AND '),
        'match_n_l', array_to_string(ARRAY(SELECT format('l.%s = n.%s', k, k) FROM unnest(v_k) AS k), ' AND '),
        'match_r_e', array_to_string(ARRAY(SELECT format('r.%s = e.%s', k, k) FROM unnest(v_k) AS k), ' AND '),
        'cc', quote_ident(v_cc),
        'mask', v_size - 1,
        'rcols', array_to_string(ARRAY(SELECT format('r.%I', c) FROM unnest(v_vals) AS c)
                                 || CASE WHEN v_versioned THEN ARRAY['r.revision', 'r.lastrevs'] ELSE '{}'::text[] END, ', '),
        'rvals', array_to_string(ARRAY(SELECT format('r.%I', c) FROM unnest(v_vals) AS c), ', '),
        -- (and vtop, the chunk version's bound of its vertex ids, as tgsis.write_chunk_rows computes it)
        'wfit', CASE WHEN cardinality(v_refs) = 0 THEN 'NULL::bigint AS vmin, true AS fits, NULL::bigint AS vtop'
                     ELSE format('min(least(%1$s)) OVER a AS vmin, '
                                 'coalesce(max(m.%2$I) OVER a - min(least(%1$s)) OVER a <= 2147483647%3$s, true) AS fits, '
                                 'CASE WHEN coalesce(max(m.%2$I) OVER a - min(least(%1$s)) OVER a <= 2147483647%3$s, true) '
                                 'THEN least((min(least(%1$s)) OVER a)::numeric + 2 * greatest(0, max(m.%2$I) OVER a '
                                 '- min(least(%1$s)) OVER a%4$s), 9223372036854775807)::bigint '
                                 'ELSE max(greatest(%1$s)) OVER a END AS vtop',
                                 array_to_string(ARRAY(SELECT format('m.%I', r) FROM unnest(v_refs) AS r), ', '), v_refs[1],
                                 coalesce((SELECT string_agg(format(' AND min(m.%1$I - m.%2$I) OVER a >= -2147483648'
                                                                    ' AND max(m.%1$I - m.%2$I) OVER a <= 2147483647', r, v_refs[1]), '')
                                             FROM unnest(v_refs[2:]) AS r), ''),
                                 coalesce((SELECT string_agg(format(', max(m.%1$I - m.%2$I) OVER a', r, v_refs[1]), '')
                                             FROM unnest(v_refs[2:]) AS r), '')) END,
        'enc', array_to_string(
            ARRAY(SELECT format('array_agg(CASE WHEN s.slot = m.slot THEN m.%1$I END ORDER BY s.slot) AS %1$I', f)
                    FROM unnest(v_floats) AS f)
            -- a vector property: its vectors as the rows of a 2-D array (a hole's and a NULL vector's: k NULLs; a vector
            -- not of k values, which the row table's CHECK refuses, would fail the aggregate, 2202E)
            || ARRAY(SELECT format('array_agg(CASE WHEN s.slot = m.slot AND m.%1$I IS NOT NULL THEN m.%1$I '
                                   'ELSE array_fill(NULL::%2$s, ARRAY[%3$s]) END ORDER BY s.slot) AS %1$I', c.name, c.typename, c.size)
                       FROM tgsis.chunk_columns(p_table) c WHERE c.role = 'vector' ORDER BY c.colorder)
            -- a point: the slots' points as the rows of a 2-D array, a hole's m NULLs (m the length of the row it
            -- comes before: every point of an object has one length, tgsis.store_in_chunks checked it)
            || ARRAY(SELECT format('array_agg(CASE WHEN s.slot = m.slot THEN m.%1$I '
                                   'ELSE array_fill(NULL::double precision, ARRAY[cardinality(m.%1$I)]) END ORDER BY s.slot) AS %1$I',
                                   c.name)
                       FROM tgsis.chunk_columns(p_table) c WHERE c.role = 'point' ORDER BY c.colorder)
            || ARRAY(SELECT format('CASE WHEN m.fits THEN array_agg(CASE WHEN m.fits AND s.slot = m.slot THEN (m.%I - %s)::integer END '
                                   'ORDER BY s.slot) END AS %I',
                                   r, CASE WHEN r = v_refs[1] THEN 'm.vmin' ELSE format('m.%I', v_refs[1]) END, r)
                     FROM unnest(v_refs) AS r)
            || ARRAY(SELECT format('CASE WHEN NOT m.fits THEN array_agg(CASE WHEN s.slot = m.slot THEN m.%1$I END ORDER BY s.slot) END AS %2$I',
                                   r, r || '_wide')
                     FROM unnest(v_refs) AS r), ', '),
        'inscols', array_to_string(v_k || ARRAY['revision', 'lastrevs', 'holes']
                                   || CASE WHEN cardinality(v_refs) > 0 THEN ARRAY['vbase', 'vtop'] ELSE '{}'::text[] END
                                   || ARRAY(SELECT quote_ident(c) FROM unnest(v_vals) AS c)
                                   || ARRAY(SELECT quote_ident(r || '_wide') FROM unnest(v_refs) AS r), ', '),
        'insvals', array_to_string(ARRAY(SELECT 'n.' || k FROM unnest(v_k) AS k) || ARRAY['n.w', 'l.lastrevs', 'n.holes']
                                   || CASE WHEN cardinality(v_refs) > 0 THEN ARRAY['n.vbase', 'n.vtop'] ELSE '{}'::text[] END
                                   || ARRAY(SELECT 'n.' || quote_ident(c) FROM unnest(v_vals) AS c)
                                   || ARRAY(SELECT 'n.' || quote_ident(r || '_wide') FROM unnest(v_refs) AS r), ', '));
    v_sql := $q$
WITH sets AS MATERIALIZED (
    SELECT 0 AS ord, v.versionid::bigint AS id, v.workingset AS revs FROM tgsis.versions v
    UNION ALL
    SELECT 1, r.revision, r.visibleset FROM tgsis.revisions r WHERE r.visibleset IS NOT NULL
), ev0 AS MATERIALIZED (
    {events}
), wsets AS MATERIALIZED (
    {wsets}
), ev AS MATERIALIZED (
    SELECT ev0.*, ws.revs FROM ev0 JOIN wsets ws ON ws.w = ev0.w
), l AS (  -- a chunk version is closed in the event revisions whose set holds its revision
    SELECT {e_K}, e.w, coalesce(array_agg(f.w ORDER BY f.w) FILTER (WHERE f.w IS NOT NULL), '{}') AS lastrevs
      FROM ev e LEFT JOIN ev f ON {match_e_f} AND f.w <> e.w AND e.w = ANY (f.revs)
     GROUP BY {e_K}, e.w
), rk AS MATERIALIZED (  -- the rows with their chunk key (joined by hash, not by the primary key's prefix)
    SELECT {rk_as}, (r.{cc} & {mask}) + 1 AS slot, {rcols}
      FROM {storage} r
), m AS (  -- the rows each event revision's set sees, by chunk and slot
    SELECT {e_K}, e.w, r.slot, {rvals}
      FROM ev e JOIN rk r ON {match_r_e}
     WHERE {vis}
), g AS (  -- each row with the slot before it in its chunk version, and the chunk version's vbase and fit
    SELECT m.*, lag(m.slot, 1, 0::bigint) OVER (PARTITION BY {m_K}, m.w ORDER BY m.slot) AS prev, {wfit}
      FROM m WINDOW a AS (PARTITION BY {m_K}, m.w)
), n AS (  -- each row expands to the holes before it and itself: slots 1 .. last, no join
    SELECT {m_K}, m.w, CASE WHEN m.fits THEN m.vmin END AS vbase, m.vtop,
           array_agg(s.slot::smallint ORDER BY s.slot) FILTER (WHERE s.slot < m.slot) AS holes, {enc}
      FROM g m CROSS JOIN LATERAL generate_series(m.prev + 1, m.slot) AS s(slot)
     GROUP BY {m_K}, m.w, m.vmin, m.fits, m.vtop
)
INSERT INTO {chunk} ({inscols})
SELECT {insvals} FROM n JOIN l ON {match_n_l} AND l.w = n.w
$q$;
    FOR v_part IN SELECT p.key, p.value FROM jsonb_each_text(v_parts) AS p ORDER BY length(p.key) DESC LOOP
        v_sql := replace(v_sql, '{' || v_part.key || '}', v_part.value);
    END LOOP;
    -- the parts hold parts ({rk_as}, {storage} in {events}): a second pass
    FOR v_part IN SELECT p.key, p.value FROM jsonb_each_text(v_parts) AS p ORDER BY length(p.key) DESC LOOP
        v_sql := replace(v_sql, '{' || v_part.key || '}', v_part.value);
    END LOOP;
    EXECUTE v_sql;
    GET DIAGNOSTICS v_n = ROW_COUNT;
    -- statistics of the new chunks: the proof's queries and, after the switch, every read are planned from them
    EXECUTE format('ANALYZE %s', v_chunk);
    PERFORM tgsis.check_chunk_conversion(p_table);
    RETURN v_n;
END
$$;

REVOKE ALL ON FUNCTION tgsis.rows_to_chunks(text) FROM PUBLIC;

COMMENT ON FUNCTION tgsis.rows_to_chunks(text) IS
    'fill the empty tgsis.<table>_chunk from the rows of the row storage (not dropped): unversioned, one chunk version of revision 0 per chunk; versioned, per chunk one version per event revision W (a row written or closed in W) holding what W''s set sees, closed in the event revisions whose set holds W; verified by tgsis.check_chunk_conversion (TG000) for every working set and revision set; returns the chunk versions written; TG201 when the chunk table holds chunks';
