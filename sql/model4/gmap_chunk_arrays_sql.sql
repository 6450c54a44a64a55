-- tgsis.gmap_chunk_arrays_sql(darts, alpha, point, period): the statement reading a G-map's involutions, points and periods from their chunk tables as arrays level by level, or no text.
-- What tgsis.gmap_conditions_hold reads when the darts and the involutions
-- of a G-map model (tgsis.gmap_dart / gmap_alpha, tgsis.md_dart / md_alpha)
-- are stored in chunks (docs/storage.md, "G-maps"): through the faces every
-- slot is decoded, and the involutions sorted by (dartid, level), an order
-- the chunk keys (geoid, level, chunk) do not give: 3.2x the rows' check.
-- Here nothing is decoded element by element: each chunk version the
-- session sees is one row of a 2-D array (its relative array as stored, a
-- hole made a sentinel by array_replace, padded to the chunk size, so that
-- no row carries a NULL bitmap, whose reads cost O(n)), with its vbase in a
-- 1-D array beside it; only the chunk rows are sorted (array_agg(... ORDER
-- BY level, chunk): a few hundred rows, not a million elements), and the
-- tests read an image as vbase + relative (tgsis.gmap_dart_tests' layout
-- ARRAY[k, s]).
-- The statement returns one row: a (int4, a row per level and chunk,
-- level-major: the relative images, a hole or padding -2^31) and a_base
-- (int8: each row's vbase less base, so that an image is the offset of its
-- dart from base, the first chunk's first id), p and p_base (the darts'
-- points, a row per chunk, padding 0), r (the darts' periods when p_period
-- is given, padding 0) and shape: the chunks are exactly those of lo..hi,
-- one version each, every level 0..n, every vbase set (no _wide chunk) and
-- within 2^31 of base (no offset overflows an int4 subscript), and the
-- present slots number darts * (n + 1) involutions and darts darts (with the
-- tests reading every slot of lo..hi, no present slot lies outside it; a
-- padding or hole read fails a test: its image lies 2^31 below base).
-- Its parameters: $1 geoid, $2 n, $3 lo, $4 hi, $5 base, $6 the number of
-- chunks k, $7 and $8 the session's viewing set for the darts and the
-- involutions when versioned (NULL otherwise), $9 the chunk size s, $10 the
-- number of darts.
-- Read as the caller: the chunk tables' row-level security, the faces'
-- visibility test and snapshot guard, as tgsis.md_vertices_in_box and
-- tgsis.chunk_object_extent read. No row (the caller reads the faces) when
-- either table is stored as rows, is not a registered G-map table of schema
-- tgsis, or its chunk table is not the caller's to read (a role granted the
-- faces only). Names come from the catalog (%I, %L), never the caller's text.
CREATE FUNCTION tgsis.gmap_chunk_arrays_sql(p_dart regclass, p_alpha regclass, p_point text, p_period text)
RETURNS TABLE (arrays text, size integer, dartset integer[], alphaset integer[], numbering text)
LANGUAGE plpgsql
STABLE
SET search_path FROM CURRENT
AS $$
DECLARE
    v_dart  text;
    v_alpha text;
    v_vis   text := '(%1$s IS NULL OR (' || tgsis.visible_versions('c', '%1$s') || '))';
BEGIN
    SELECT c.relname INTO v_dart FROM pg_catalog.pg_class c WHERE c.oid = p_dart AND c.relnamespace = 'tgsis'::regnamespace;
    SELECT c.relname INTO v_alpha FROM pg_catalog.pg_class c WHERE c.oid = p_alpha AND c.relnamespace = 'tgsis'::regnamespace;
    SELECT d.chunksize INTO size
      FROM tgsis.model_tables d JOIN tgsis.model_tables a ON a.chunksize = d.chunksize
     WHERE d.tablename = v_dart AND d.chunkcolumn = 'dartid' AND p_point = ANY (d.chunkrefs)
       AND a.tablename = v_alpha AND a.chunkcolumn = 'dartid' AND a.chunkrefs = ARRAY['dartid2'];
    IF size IS NULL OR NOT tgsis.stored_in_chunks(v_dart) OR NOT tgsis.stored_in_chunks(v_alpha)
       OR to_regclass(format('tgsis.%I', v_dart || '_chunk')) IS NULL OR to_regclass(format('tgsis.%I', v_alpha || '_chunk')) IS NULL
       OR NOT has_table_privilege(to_regclass(format('tgsis.%I', v_dart || '_chunk')), 'SELECT')
       OR NOT has_table_privilege(to_regclass(format('tgsis.%I', v_alpha || '_chunk')), 'SELECT')
       OR (p_period IS NOT NULL
           AND NOT EXISTS (SELECT FROM pg_catalog.pg_attribute t
                            WHERE t.attrelid = to_regclass(format('tgsis.%I', v_dart || '_chunk')) AND t.attname = p_period
                              AND t.atttypid = 'double precision[]'::regtype AND NOT t.attisdropped)) THEN
        RETURN;
    END IF;
    IF EXISTS (SELECT FROM tgsis.versioned_tables t WHERE t.schemaname = 'tgsis' AND t.tablename = v_dart) THEN
        dartset := tgsis.get_revisions(true);
    END IF;
    IF EXISTS (SELECT FROM tgsis.versioned_tables t WHERE t.schemaname = 'tgsis' AND t.tablename = v_alpha) THEN
        alphaset := tgsis.get_revisions(true);
    END IF;
    arrays := format(
        'SELECT i.a, i.a_base, d.p, d.p_base, d.r, '
        '       (i.rows = ($2 + 1) * $6 AND i.keys = i.rows AND i.lolevel = 0 AND i.hilevel = $2 '
        '        AND i.lochunk = $5 / $9 AND i.hichunk = $5 / $9 + $6 - 1 AND i.present = $10 * ($2 + 1) '
        '        AND i.wide = 0 AND i.lobase >= -2147483648 AND i.hibase <= 2147483647 '
        '        AND d.rows = $6 AND d.keys = d.rows AND d.lochunk = $5 / $9 AND d.hichunk = $5 / $9 + $6 - 1 '
        '        AND d.wide = 0 AND d.present = $10) IS TRUE AS shape '
        '  FROM (SELECT array_agg((array_replace(c.dartid2, NULL, -2147483648) '
        '                          || array_fill(-2147483648, ARRAY[greatest($9 - cardinality(c.dartid2), 0)]))[1:$9] '
        '                         ORDER BY c.level, c.chunk) AS a, '
        '               array_agg(c.vbase - $5 ORDER BY c.level, c.chunk) AS a_base, '
        '               count(*) AS rows, count(DISTINCT (c.level, c.chunk)) AS keys, min(c.level) AS lolevel, '
        '               max(c.level) AS hilevel, min(c.chunk) AS lochunk, max(c.chunk) AS hichunk, '
        '               min(c.vbase - $5) AS lobase, max(c.vbase - $5) AS hibase, '
        '               count(*) FILTER (WHERE c.vbase IS NULL OR c.dartid2 IS NULL) AS wide, '
        '               sum(cardinality(c.dartid2) - cardinality(array_positions(c.dartid2, NULL))) AS present '
        '          FROM %1$s c '
        '         WHERE (SELECT tgsis.chunk_snapshot_guard(%2$L::regclass)) AND c.geoid = $1 AND %3$s) AS i, '
        '       (SELECT array_agg((array_replace(c.%4$I, NULL, 0) || array_fill(0, ARRAY[greatest($9 - cardinality(c.%4$I), 0)]))[1:$9] '
        '                         ORDER BY c.chunk) AS p, '
        '               array_agg(c.vbase ORDER BY c.chunk) AS p_base, '
        '               %5$s AS r, '
        '               count(*) AS rows, count(DISTINCT c.chunk) AS keys, min(c.chunk) AS lochunk, max(c.chunk) AS hichunk, '
        '               count(*) FILTER (WHERE c.vbase IS NULL OR c.%4$I IS NULL) AS wide, '
        '               sum(cardinality(c.%4$I) - cardinality(array_positions(c.%4$I, NULL))) AS present '
        '          FROM %6$s c '
        '         WHERE (SELECT tgsis.chunk_snapshot_guard(%7$L::regclass)) AND c.geoid = $1 AND %8$s) AS d',
        format('tgsis.%I', v_alpha || '_chunk'), format('tgsis.%I', v_alpha || '_chunk'), format(v_vis, '$8'),
        p_point,
        CASE WHEN p_period IS NULL THEN 'NULL::double precision[]'
             ELSE format('array_agg((array_replace(c.%1$I, NULL, 0) || array_fill(0::double precision, ARRAY[greatest($9 - cardinality(c.%1$I), 0)]))[1:$9] ORDER BY c.chunk)', p_period) END,
        format('tgsis.%I', v_dart || '_chunk'), format('tgsis.%I', v_dart || '_chunk'), format(v_vis, '$7'));
    -- the darts' numbering from the chunk rows (what tgsis.gmap_conditions asks before the proof): a chunk's
    -- present slots are its point array's length less its NULLs, its first and last the array's ends unless a
    -- hole lies there; several periods unless every chunk holds one value (array_positions: float8's =, as
    -- min < max compares) and all chunks the same. Parameters: $1 geoid, $2 the darts' viewing set.
    numbering := format(
        'SELECT min(c.chunk * %1$s + f.first - 1), max(c.chunk * %1$s + f.last - 1), coalesce(sum(f.present), 0)::bigint, %2$s '
        '  FROM %3$s c '
        ' CROSS JOIN LATERAL (SELECT cardinality(c.%4$I) - cardinality(array_positions(c.%4$I, NULL)) AS present, '
        '                            CASE WHEN c.%4$I[1] IS NOT NULL THEN 1 '
        '                                 ELSE (SELECT min(u.o) FROM unnest(c.%4$I) WITH ORDINALITY AS u (x, o) WHERE u.x IS NOT NULL) END AS first, '
        '                            CASE WHEN c.%4$I[cardinality(c.%4$I)] IS NOT NULL THEN cardinality(c.%4$I) '
        '                                 ELSE (SELECT max(u.o) FROM unnest(c.%4$I) WITH ORDINALITY AS u (x, o) WHERE u.x IS NOT NULL) END AS last) AS f '
        ' WHERE (SELECT tgsis.chunk_snapshot_guard(%5$L::regclass)) AND c.geoid = $1 AND %6$s',
        size,
        CASE WHEN p_period IS NULL THEN 'false'
             ELSE format('count(DISTINCT c.%1$I[f.first]) > 1 '
                         'OR bool_or(f.present > 0 AND cardinality(array_positions(c.%1$I, c.%1$I[f.first])) <> f.present)', p_period) END,
        format('tgsis.%I', v_dart || '_chunk'), p_point, format('tgsis.%I', v_dart || '_chunk'), format(v_vis, '$2'));
    RETURN NEXT;
END
$$;

COMMENT ON FUNCTION tgsis.gmap_chunk_arrays_sql(regclass, regclass, text, text) IS
    'the statement (with its chunk size and viewing sets) that reads a G-map''s involutions, points and periods from their chunk tables as 2-D arrays, a row per chunk version (and level), with each row''s vbase (tgsis.gmap_dart_tests'' layout ARRAY[k, s]; shape: the chunks and slots are exactly those of darts lo..hi), as the caller; no row when either table is stored as rows or its chunk table is not the caller''s to read; what tgsis.gmap_conditions_hold reads on chunks; numbering: the statement giving the darts'' first and last id, their number and whether they lie in several periods from the chunk rows (what tgsis.gmap_conditions asks first)';
