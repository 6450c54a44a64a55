-- tgsis.storage_changed_rows(schema, table, geoids, base, parent, child): the relation of a table's stored row versions the three states of a merge may see otherwise, sized by the slots that changed.
-- The merges' readers of "what changed since the base" (tgsis.mesh_merge_work's
-- changed keys, tgsis.conflict_discards, the Python merge's change,
-- src/tgsis/db/_merge_states.py) read the row versions written or closed in the
-- revisions that tell the three sets apart. On rows those are the changed rows.
-- A table stored in chunks writes a whole chunk version for a change of one slot,
-- so every slot of a changed chunk looked changed: 1,024 keys per chunk for one
-- moved vertex, and the regions' work, the discards and the merged mesh's
-- validity were sized by chunks, not by the change (issue 40). Here, of a table
-- stored in chunks, the chunks (by their key, tgsis.chunk_key: an instant's
-- chunks of model 2 apart) with a version written or closed in those
-- revisions are compared slot by slot between the chunk versions the base, the
-- parent and the child see (each at most one): a slot is changed when its
-- presence differs (a hole, NULL first column or holes) or any of its decoded
-- values differs bit for bit (floats by their send forms: -0.0 is not 0.0, NaN
-- payloads differ; vertex ids decoded from vbase or _wide, so a chunk re-based
-- is not a change). The relation is then the decoding of those chunks' versions
-- (every version, as storage_row_versions gives them) restricted to the changed
-- slots: a superset of what merge3 counts as a change (it compares -0.0 equal to
-- 0.0), never less, and a slot written again with the same bits is left out, as
-- a row rewritten with its own values changes nothing. The caller filters on the
-- object key and the versioning columns as on rows. The comparison is in the SQL
-- returned, read with the caller's rights; SECURITY DEFINER only to read the
-- decoding pieces (tgsis.chunk_decode_sql, tgsis.chunk_columns: the chunks layer,
-- above this one, named at run time). Not stored in chunks: storage_row_versions'
-- relation (<table>_ver), the callers' filter on the revisions gives the rows.
CREATE FUNCTION tgsis.storage_changed_rows(p_schema text, p_table text, p_geoids bigint[], p_base integer[],
                                           p_parent integer[], p_child integer[])
RETURNS text
LANGUAGE plpgsql
STABLE
SECURITY DEFINER
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_dec   record;
    v_since integer[];
    v_sig   text;
    v_one   text;
    v_side  text[] := '{}';
    v_a     text;
    v_key   text[];  -- the chunk key before chunk (tgsis.chunk_key: geoid; geoid, times for model 2)
    v_kk    text;    -- k's key columns, then chunk
BEGIN
    IF p_schema IS DISTINCT FROM 'tgsis' OR NOT tgsis.stored_in_chunks(p_table) THEN
        RETURN tgsis.storage_row_versions(p_schema, p_table);
    END IF;
    p_base := coalesce(p_base, '{}');
    p_parent := coalesce(p_parent, '{}');
    p_child := coalesce(p_child, '{}');
    -- the revisions not in all three sets: a chunk version seen by some and not all was written or closed in one
    v_since := ARRAY(SELECT r FROM unnest(p_base || p_parent || p_child) AS r
                     EXCEPT (SELECT r FROM unnest(p_base) AS r INTERSECT SELECT r FROM unnest(p_parent) AS r
                             INTERSECT SELECT r FROM unnest(p_child) AS r)
                     ORDER BY 1);
    EXECUTE format('SELECT tgsis.%I($1)', 'chunk_key') INTO v_key USING p_table;
    v_kk := array_to_string(ARRAY(SELECT format('k.%I', k) FROM unnest(v_key) AS k) || 'k.chunk'::text, ', ');
    -- a slot's signature: its decoded values, floats and points by their send forms (bit for bit); true first, never NULL
    EXECUTE format('SELECT string_agg(CASE WHEN c.role IN (%L, %L) AND c.typename = %L THEN format(%L, c.name)
                                           WHEN c.role IN (%L, %L) AND c.typename = %L THEN format(%L, c.name)
                                           WHEN c.role = %L THEN format(%L, c.name)
                                           ELSE format(%L, c.name) END, %L ORDER BY c.colorder)
                      FROM tgsis.%I($1) AS c WHERE c.role IN (%L, %L, %L, %L)',
                   'float', 'value', 'double precision', 'float8send(s.%I)',
                   'float', 'value', 'real', 'float4send(s.%I)', 'point', 'array_send(s.%I)', 's.%I', ', ',
                   'chunk_columns', 'float', 'value', 'ref', 'point')
       INTO v_sig USING p_table;
    FOREACH v_a IN ARRAY ARRAY['b', 'p', 'q'] LOOP
        EXECUTE format('SELECT d.select_list, d.arrays, d.aliases, d.present, d.joins FROM tgsis.%I($1, $2) AS d', 'chunk_decode_sql')
           INTO v_dec USING p_table, v_a;
        -- the slots present in the chunk version the set sees, with their signatures
        v_side := v_side || format(
            '(SELECT s.o, ROW(true, %s) AS sig
                FROM (SELECT u.o, %s FROM tgsis.%I %s%s CROSS JOIN LATERAL unnest(%s) WITH ORDINALITY AS u(%s, o)
                       WHERE %s AND %s.revision = ANY (%L::integer[])
                         AND NOT (%s.revclosed AND %s.lastrevs && %L::integer[]) AND %s) AS s)',
            v_sig, v_dec.select_list, p_table || '_chunk', v_a, v_dec.joins, v_dec.arrays, v_dec.aliases,
            (SELECT string_agg(format('%I.%I = k.%I', v_a, k, k), ' AND ') FROM unnest(v_key || 'chunk'::text) AS k),
            v_a, CASE v_a WHEN 'b' THEN p_base WHEN 'p' THEN p_parent ELSE p_child END,
            v_a, v_a, CASE v_a WHEN 'b' THEN p_base WHEN 'p' THEN p_parent ELSE p_child END, v_dec.present);
    END LOOP;
    v_one := format(
        '(SELECT %s, ARRAY(SELECT coalesce(b.o, p.o, q.o) FROM %s AS b FULL JOIN %s AS p ON p.o = b.o
                                           FULL JOIN %s AS q ON q.o = coalesce(b.o, p.o)
                                          WHERE b.sig IS DISTINCT FROM p.sig OR b.sig IS DISTINCT FROM q.sig) AS slots
            FROM (SELECT DISTINCT %s FROM tgsis.%I c
                   WHERE c.%I = ANY (%L::bigint[])
                     AND (c.revision = ANY (%L::integer[]) OR (c.revclosed AND c.lastrevs && %L::integer[]))) AS k)',
        v_kk, v_side[1], v_side[2], v_side[3],
        array_to_string(ARRAY(SELECT format('c.%I', k) FROM unnest(v_key) AS k) || 'c.chunk'::text, ', '),
        p_table || '_chunk', v_key[1], coalesce(p_geoids, '{}'), v_since, v_since);
    EXECUTE format('SELECT d.select_list, d.arrays, d.aliases, d.present, d.joins FROM tgsis.%I($1, $2) AS d', 'chunk_decode_sql')
       INTO v_dec USING p_table, 'c';
    -- (the changed slots MATERIALIZED: computed once per chunk, not per decoded slot that tests them)
    RETURN format('(WITH w AS MATERIALIZED %s
                    SELECT %s, c.revision, c.lastrevs, c.revclosed
                      FROM w JOIN tgsis.%I c ON %s AND cardinality(w.slots) > 0%s
                     CROSS JOIN LATERAL unnest(%s) WITH ORDINALITY AS u(%s, o)
                     WHERE %s AND u.o = ANY (w.slots)
                       AND (c.revision = ANY (%L::integer[]) OR (c.revclosed AND c.lastrevs && %L::integer[])))',
                  v_one, v_dec.select_list, p_table || '_chunk',
                  (SELECT string_agg(format('c.%I = w.%I', k, k), ' AND ') FROM unnest(v_key || 'chunk'::text) AS k),
                  v_dec.joins, v_dec.arrays, v_dec.aliases, v_dec.present,
                  v_since, v_since);
END
$$;

COMMENT ON FUNCTION tgsis.storage_changed_rows(text, text, bigint[], integer[], integer[], integer[]) IS
    'SQL of the relation of a table''s stored row versions (the row table''s columns, then revision, lastrevs, revclosed) that the three sets of a merge (base, parent, child) may see otherwise: stored in chunks, the versions written or closed in the revisions not in all three sets, of the objects p_geoids, decoded only at the slots whose presence or values (bit for bit) differ between the chunk versions the three sets see; else tgsis.storage_row_versions'' relation (the caller filters the revisions)';

-- internal to the merges' readers, not executable by PUBLIC (tests/test_function_grants.py); the tgsis roles run it as themselves
REVOKE ALL ON FUNCTION tgsis.storage_changed_rows(text, text, bigint[], integer[], integer[], integer[]) FROM PUBLIC;
GRANT EXECUTE ON FUNCTION tgsis.storage_changed_rows(text, text, bigint[], integer[], integer[], integer[]) TO tgsis_reader;
