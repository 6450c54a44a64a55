-- tgsis.chunk_insert_check(): AFTER INSERT statement trigger on every tgsis.<table>_chunk: chunk versions a role inserts directly are encoded as read, and unversioned storage keeps one open version of revision 0 per chunk.
-- Roles other than the owners keep INSERT on the chunk table (the client's
-- COPY upload of new objects writes chunks directly); everything else goes
-- through the face (tgsis.write_chunk_rows), which encodes what it writes.
-- Row storage cannot hold a malformed row (NOT NULL, CHECKs, its key); a
-- chunk table could hold a chunk its readers decode differently, so the
-- statement's new chunk versions (its transition table, once per statement)
-- are checked:
-- 1. their encoding, by the conditions the conversion's proof checks too
--    (tgsis.chunk_encoding_checks): a chunk breaking one fails the statement
--    (23514, as a CHECK of the row table would), naming the object and chunk;
-- 2. while the table is not versioned (tgsis.versioned_tables, read at each
--    statement: enable_feature_versioning needs no new trigger), each is open
--    and of revision 0, as tgsis.write_chunk_rows writes unversioned storage:
--    the key (object, chunk, revision) takes another revision or a closed
--    version, which the face hides and the readers and a later
--    enable_feature_versioning would see (23514 too). Versioned
--    tables are checked by tgsis.storage_rows_check (tgsis.guard_chunk_storage).
-- The trigger's WHEN spares the chunk table's and tgsis's owners (the face's
-- writer, the conversions, merges), made by tgsis.create_chunk_table.
-- Trigger argument: the model table's name. Definer's rights (it reads the
-- registry for a role that may hold INSERT alone); search_path pinned.
CREATE FUNCTION tgsis.chunk_insert_check()
RETURNS trigger
LANGUAGE plpgsql
VOLATILE
SECURITY DEFINER
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_table text := TG_ARGV[0];
    v_keys  text[];
    v_bad   record;
BEGIN
    v_keys := tgsis.chunk_key(v_table);
    EXECUTE format('SELECT concat_ws(%1$L, %2$s) AS object, c.chunk, c.revision, count(*) OVER () AS n '
                   'FROM tgsis_new_chunks c WHERE NOT coalesce(%3$s, false) ORDER BY 1, 2, 3 LIMIT 1',
                   ', ', (SELECT string_agg(format('%L || c.%I', k || ' ', k), ', ') FROM unnest(v_keys) AS k),
                   array_to_string(tgsis.chunk_encoding_checks(v_table), ' AND ')) INTO v_bad;
    IF v_bad.chunk IS NOT NULL THEN
        RAISE EXCEPTION 'new chunk of %.% is not encoded as its readers read it: object %, chunk %, revision %',
                        TG_TABLE_SCHEMA, TG_TABLE_NAME, v_bad.object, v_bad.chunk, v_bad.revision
            USING ERRCODE = 'check_violation',
                  DETAIL = format('%s chunk version(s) inserted with arrays not one-dimensional from 1, of unequal length or '
                                  'longer than a chunk, ending on a hole, NULL elsewhere than at their holes, without a '
                                  'coordinate array, with refs both relative and absolute, or with a vtop that does not bound the '
                                  'vertex ids (docs/storage.md, '
                                  '"Chunks and the mapping of ids").', v_bad.n),
                  HINT = format('write the rows through the view %s, which encodes them', tgsis.chunk_relation(v_table, ''));
    END IF;
    IF NOT EXISTS (SELECT FROM tgsis.versioned_tables t, tgsis.chunk_registry(v_table) r
                    WHERE t.schemaname = r.schemaname AND t.tablename = r.tablename) THEN
        EXECUTE format('SELECT concat_ws(%1$L, %2$s) AS object, c.chunk, c.revision, count(*) OVER () AS n '
                       'FROM tgsis_new_chunks c WHERE c.revision IS DISTINCT FROM 0 OR c.lastrevs IS DISTINCT FROM ''{}'' '
                       'ORDER BY 1, 2, 3 LIMIT 1',
                       ', ', (SELECT string_agg(format('%L || c.%I', k || ' ', k), ', ') FROM unnest(v_keys) AS k)) INTO v_bad;
        IF v_bad.chunk IS NOT NULL THEN
            RAISE EXCEPTION '%.% is not versioned: a chunk version inserted directly must be open and of revision 0 (object %, chunk %, revision %)',
                            TG_TABLE_SCHEMA, TG_TABLE_NAME, v_bad.object, v_bad.chunk, v_bad.revision
                USING ERRCODE = 'check_violation',
                      DETAIL = format('%s chunk version(s) inserted with another revision or closed; unversioned storage '
                                      'holds one open version of revision 0 per chunk.', v_bad.n),
                      HINT = format('write the rows through the view %s, which encodes them', tgsis.chunk_relation(v_table, ''));
        END IF;
    END IF;
    RETURN NULL;
END
$$;

REVOKE ALL ON FUNCTION tgsis.chunk_insert_check() FROM PUBLIC;

COMMENT ON FUNCTION tgsis.chunk_insert_check() IS
    'AFTER INSERT statement trigger of tgsis.<table>_chunk (transition table tgsis_new_chunks) for roles other than the owners: new chunk versions must be encoded as their readers read them (tgsis.chunk_encoding_checks; 23514), and open and of revision 0 while the table is not versioned (23514)';
