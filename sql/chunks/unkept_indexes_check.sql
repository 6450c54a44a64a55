-- tgsis.unkept_indexes_check(storage, chunks, switch): refuse (TG202) a storage switch that would drop an index of a DBA's without a word.
-- The switches keep a row table's own secondary indexes on its row definition
-- (tgsis.move_row_indexes) and make them again on the way back; what they
-- cannot keep they now refuse, by name, before anything changes:
-- * into chunks (p_chunks false: p_storage is the row storage, <table>_ver when
--   versioned): an index that names revision, lastrevs or revclosed (a key
--   column, an expression or the predicate) and is not one of the versioning's
--   own (tgsis.enable_versioning_rel, tgsis.create_revision_indexes: a BRIN on
--   revision alone, a btree on the object key WHERE revclosed, a btree on the
--   object key and revision named <table>_ver_object_idx), which the chunk table replaces with its own:
--   those columns go with the row versions, so the index cannot be kept;
-- * back into rows (p_chunks true: p_storage is the chunk table): any index
--   but the chunk table's own (tgsis.create_chunk_table: its key, a BRIN on
--   revision alone, a btree on the key WHERE revclosed, the GiST on
--   tgsis.point_chunk_box): the chunk table is dropped with it.
-- Before, both were dropped with their table (same answers, slower, nothing
-- said; tests/test_chunk_review5.py). The HINT: drop it, switch, make it again
-- on the new storage if it still applies (tgsis.storage_table names it), the
-- statements after 'in psql: ' (the command's hint mapping leaves them be).
-- Runs with the caller's rights, inside the switches (which check theirs).
CREATE FUNCTION tgsis.unkept_indexes_check(p_storage regclass, p_chunks boolean, p_switch text)
RETURNS void
LANGUAGE plpgsql
STABLE
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_idx record;
BEGIN
    FOR v_idx IN
        SELECT i.indexrelid::regclass AS idx, pg_get_indexdef(i.indexrelid) AS def
          FROM pg_index i
          JOIN pg_class c ON c.oid = i.indexrelid
          JOIN pg_am m ON m.oid = c.relam
         WHERE i.indrelid = p_storage AND NOT i.indisprimary
           AND NOT EXISTS (SELECT FROM pg_constraint con WHERE con.conindid = i.indexrelid AND con.conrelid = p_storage)
           -- the versioning's columns named by the index (its key columns, expressions or predicate: pg_depend),
           -- or any index of a chunk table
           AND (p_chunks
                OR EXISTS (SELECT FROM pg_depend d
                             JOIN pg_attribute a ON a.attrelid = d.refobjid AND a.attnum = d.refobjsubid
                            WHERE d.classid = 'pg_class'::regclass AND d.objid = i.indexrelid
                              AND d.refclassid = 'pg_class'::regclass AND d.refobjid = p_storage AND d.refobjsubid > 0
                              AND a.attname IN ('revision', 'lastrevs', 'revclosed')))
           -- not tgsis's own, by shape
           AND NOT (m.amname = 'brin' AND i.indnatts = 1 AND i.indpred IS NULL AND i.indexprs IS NULL
                    AND (SELECT a.attname FROM pg_attribute a WHERE a.attrelid = p_storage AND a.attnum = i.indkey[0]) = 'revision')
           AND NOT (m.amname = 'btree' AND i.indnatts = 1 AND i.indexprs IS NULL AND i.indkey[0] <> 0
                    AND pg_get_expr(i.indpred, i.indrelid) = 'revclosed')
           AND NOT (NOT p_chunks AND m.amname = 'btree' AND i.indnatts = 2 AND i.indpred IS NULL AND i.indexprs IS NULL
                    AND i.indoption::int2[] = '{0,0}'
                    AND c.relname = (SELECT s.relname FROM pg_class s WHERE s.oid = p_storage) || '_object_idx'
                    AND (SELECT a.attname FROM pg_attribute a WHERE a.attrelid = p_storage AND a.attnum = i.indkey[1]) = 'revision')
           AND NOT (p_chunks AND m.amname = 'gist' AND i.indnatts = 1 AND i.indkey[0] = 0 AND i.indpred IS NULL
                    AND pg_get_expr(i.indexprs, i.indrelid) LIKE 'tgsis.point_chunk_box(%')
         ORDER BY c.relname
         LIMIT 1
    LOOP
        RAISE EXCEPTION '% cannot go on: the index % of % would be dropped with it', p_switch, v_idx.idx, p_storage
            USING ERRCODE = 'TG202',
                  DETAIL = format('%s; %s', v_idx.def,
                                  CASE WHEN p_chunks
                                       THEN 'the chunk table is dropped by the way back into rows and only its own indexes are tgsis''s'
                                       ELSE 'it names the row versions'' revision columns (revision, lastrevs, revclosed), which '
                                            'the chunk storage does not have as columns' END
                                  || '; nothing was changed.'),
                  HINT = format('drop the index, switch, then make it again on the new storage if it still applies (in psql: '
                                'DROP INDEX %s; then %s; SELECT tgsis.storage_table(schema, table) names the new storage)',
                                v_idx.idx, p_switch);
    END LOOP;
END
$$;

COMMENT ON FUNCTION tgsis.unkept_indexes_check(regclass, boolean, text) IS
    'refuse (TG202, naming it) a storage switch that would drop an index it cannot keep: into chunks, an index of the row storage that names revision, lastrevs or revclosed and is not the versioning''s own; back into rows, any index of the chunk table but its own; nothing changed';

-- internal to the storage switches (tgsis.store_in_chunks, store_in_rows, store_class_in_chunks, store_class_in_rows)
REVOKE ALL ON FUNCTION tgsis.unkept_indexes_check(regclass, boolean, text) FROM PUBLIC;
