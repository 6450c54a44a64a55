-- tgsis.check_chunk_conversion(table): raise unless the decoded chunks of tgsis.<table>_chunk show every set exactly the rows the row storage shows it.
-- The proof both conversions give before they return (tgsis.rows_to_chunks,
-- tgsis.chunks_to_rows; docs/storage.md, "Upgrading an existing database,
-- and back"): a difference raises, so the caller's transaction changes
-- nothing. Versioned storage (tgsis.versioned_tables): for every version's
-- working set and every revision's stored set (tgsis.revisions.visibleset,
-- what goto_revision shows), the rows visible in it (revision in the set,
-- lastrevs meeting none of it) against the chunk versions visible in it,
-- decoded by tgsis.<table>_chunk_rows; unversioned storage: every row against
-- every chunk version, which must be open and of revision 0 (any other
-- shows as a difference). Row for row with
-- duplicates (EXCEPT ALL both ways: a set seeing two chunk versions of one
-- chunk shows a key twice), value for value: doubles by their bits
-- (float8send: -0.0, NaN payloads), a vector property or a point by its array_send
-- (its elements' bits, its shape), ids and keys as they are. Raises TG000
-- naming the table, the object (geoid and the other key columns), the chunk
-- and the set of the first difference, with the count of differing rows.
-- Called on a table already stored in chunks (its storage is the chunk
-- table: no rows to compare with), it checks the encoding of every chunk
-- version and returns.
-- Internal: runs with the caller's rights (tgsis's owner).
CREATE FUNCTION tgsis.check_chunk_conversion(p_table text)
RETURNS void
LANGUAGE plpgsql
VOLATILE
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_reg      record;
    v_storage  regclass;
    v_view     regclass;
    v_shift    integer;
    v_keys     text[];
    v_cols     text;    -- the compared columns of a row r
    v_versioned boolean;
    v_sets     text;
    v_rvis     text;
    v_cvis     text;
    v_rextra   text := '';  -- unversioned: the revision and lastrevs a chunk version must have, against its own
    v_cextra   text := '';
    v_bad      record;
    v_enc      text[];  -- the encoding's conditions on a chunk version c (tgsis.chunk_encoding_checks)
BEGIN
    PERFORM tgsis.chunk_table_of(p_table, true);  -- TG200 / TG100
    SELECT * INTO v_reg FROM tgsis.chunk_registry(p_table) r;
    v_view := tgsis.chunk_relation(p_table, '_chunk_rows')::regclass;
    v_storage := tgsis.storage_table(v_reg.schemaname, v_reg.tablename)::regclass;
    v_shift := round(log(2, v_reg.chunksize))::integer;
    v_keys := tgsis.chunk_key(p_table);
    -- floating-point values by their bits (-0.0, NaN payloads), the rest as they are
    v_cols := (SELECT string_agg(CASE WHEN c.role IN ('vector', 'point') THEN format('array_send(r.%1$I) AS %1$I', c.name)  -- (its elements' bits)
                                      WHEN c.role = 'float' OR c.typename = 'double precision' THEN format('float8send(r.%1$I) AS %1$I', c.name)
                                      WHEN c.typename = 'real' THEN format('float4send(r.%1$I) AS %1$I', c.name)
                                      ELSE format('r.%I', c.name) END, ', ' ORDER BY c.colorder)
                 FROM tgsis.chunk_columns(p_table) c);
    v_versioned := EXISTS (SELECT FROM tgsis.versioned_tables t WHERE t.schemaname = v_reg.schemaname AND t.tablename = v_reg.tablename);
    -- the encoding of every chunk version (the conditions a direct insert is checked for too)
    v_enc := tgsis.chunk_encoding_checks(p_table);
    EXECUTE format('SELECT concat_ws(%1$L, %2$s) AS object, c.chunk, c.revision, count(*) OVER () AS n FROM %3$s c '
                   'WHERE NOT coalesce(%4$s, false) ORDER BY 1, 2, 3 LIMIT 1',
                   ', ', (SELECT string_agg(format('%L || c.%I', k || ' ', k), ', ') FROM unnest(v_keys) AS k),
                   tgsis.chunk_relation(p_table, '_chunk'), array_to_string(v_enc, ' AND ')) INTO v_bad;
    IF v_bad.chunk IS NOT NULL THEN
        RAISE EXCEPTION 'a chunk of % is not encoded as its readers read it: object %, chunk %, revision %',
                        tgsis.chunk_relation(p_table, ''), v_bad.object, v_bad.chunk, v_bad.revision
            USING ERRCODE = 'TG000',
                  DETAIL = format('%s chunk version(s) of %s with arrays not one-dimensional from 1, of unequal length, '
                                  'ending on a hole, NULL elsewhere than at their holes, refs both relative and absolute, or a vtop '
                                  'that does not bound the vertex ids.',
                                  v_bad.n, tgsis.chunk_relation(p_table, '_chunk')),
                  HINT = 'nothing was converted; report it with the table, object, chunk and set';
    END IF;
    -- once switched, the chunks are the storage (tgsis.storage_table names them): no rows are left to compare
    -- with, and the face decodes what the encoding check above has checked
    IF v_storage = tgsis.chunk_relation(p_table, '_chunk')::regclass THEN
        RETURN;
    END IF;
    IF v_versioned THEN
        v_sets := 'SELECT format(''the working set of version %L'', v.name) AS label, v.workingset AS revs FROM tgsis.versions v
                   UNION ALL
                   SELECT format(''the set of revision %s'', r.revision), r.visibleset FROM tgsis.revisions r
                    WHERE r.visibleset IS NOT NULL';
        v_rvis := 'r.revision = ANY (s.revs) AND NOT (r.lastrevs && s.revs)';
        v_cvis := v_rvis;
    ELSE
        v_sets := 'SELECT ''the unversioned storage''::text AS label, ARRAY[0] AS revs';
        v_rvis := 'true';
        v_cvis := 'true';  -- every chunk version counts: unversioned storage has only open ones of revision 0
        v_rextra := ', 0 AS revision, ''{}''::integer[] AS lastrevs';
        v_cextra := ', r.revision, r.lastrevs';
    END IF;
    EXECUTE format(
        'WITH s AS MATERIALIZED (%1$s),
              rw AS (SELECT s.label, %2$s%11$s FROM s CROSS JOIN %3$s r WHERE %4$s),
              ch AS (SELECT s.label, %2$s%12$s FROM s CROSS JOIN %5$s r WHERE %6$s),
              d AS ((SELECT * FROM rw EXCEPT ALL SELECT * FROM ch) UNION ALL (SELECT * FROM ch EXCEPT ALL SELECT * FROM rw))
         SELECT d.label, concat_ws(%7$L, %8$s) AS object, d.%9$I >> %10$s AS chunk, count(*) OVER () AS n FROM d
          ORDER BY 2, 3, 1 LIMIT 1',
        v_sets, v_cols, v_storage, v_rvis, v_view, v_cvis, ', ',
        (SELECT string_agg(format('%L || d.%I', k || ' ', k), ', ') FROM unnest(v_keys) AS k),
        v_reg.chunkcolumn, v_shift, v_rextra, v_cextra) INTO v_bad;
    IF v_bad.label IS NOT NULL THEN
        RAISE EXCEPTION 'the chunks of % differ from its rows: object %, chunk %, in %', tgsis.chunk_relation(p_table, ''),
                        v_bad.object, v_bad.chunk, v_bad.label
            USING ERRCODE = 'TG000',
                  DETAIL = format('%s row(s) differ over all sets (a row missing or extra on one side, or a value not the same bits); '
                                  '%s against %s.', v_bad.n, v_view, v_storage),
                  HINT = 'nothing was converted; report it with the table, object, chunk and set';
    END IF;
END
$$;

REVOKE ALL ON FUNCTION tgsis.check_chunk_conversion(text) FROM PUBLIC;

COMMENT ON FUNCTION tgsis.check_chunk_conversion(text) IS
    'raise TG000 (naming table, object, chunk and set) unless, for every version''s working set and every revision''s stored set (unversioned storage: every row against every chunk version), the decoded chunks of tgsis.<table>_chunk equal the rows of the row storage visible in it, row for row and value for value (doubles by float8send); on a table stored in chunks already, the encoding of every chunk version alone';
