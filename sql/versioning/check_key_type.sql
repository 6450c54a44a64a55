-- tgsis.check_key_type(storage, column): refuse (TG100) an object key column whose type is not built into PostgreSQL.
-- tgsis's definer code casts object keys to and from text as tgsis's owner
-- (validating keys, reading keys of rows written directly). enable_versioning
-- refuses such keys, but a table's owner can change the column's type
-- afterwards; a domain's check or a cast of a type of its own would then be
-- the owner's code run as tgsis's owner. So the definer code checks the type
-- again each time, before it casts. A column missing because the storage was
-- made after the transaction's snapshot (a storage switch: the snapshot sees
-- no column of it, and would read it empty) is 40001 (retry), not TG100:
-- tgsis.chunk_snapshot_guard says so first (find_conflicts under an older
-- REPEATABLE READ snapshot; tests/test_old_snapshot_chunk_readers.py).
CREATE FUNCTION tgsis.check_key_type(p_storage regclass, p_column text)
RETURNS void
LANGUAGE plpgsql
STABLE
AS $$
DECLARE
    v_type oid := (SELECT a.atttypid FROM pg_catalog.pg_attribute a
                    WHERE a.attrelid = p_storage AND a.attname = p_column AND NOT a.attisdropped);
BEGIN
    IF v_type IS NULL THEN
        PERFORM tgsis.chunk_snapshot_guard(p_storage);  -- 40001 when the storage is newer than the snapshot
    END IF;
    IF v_type IS NULL OR v_type >= 16384 THEN
        RAISE EXCEPTION 'the object key column % of % is %', quote_ident(p_column), p_storage,
                CASE WHEN v_type IS NULL THEN 'missing' ELSE format('of type %s, which is not built into PostgreSQL',
                                                                   pg_catalog.format_type(v_type, NULL)) END
            USING ERRCODE = 'TG100',
                  DETAIL = 'tgsis reads and compares object keys as its owner; a type of one''s own could run its owner''s code there.',
                  HINT = 'key the objects by a column of a built-in type (integer, bigint, text, uuid, ...)';
    END IF;
END
$$;

COMMENT ON FUNCTION tgsis.check_key_type(regclass, text) IS
    'raise TG100 unless the object key column of a versioned table''s storage is of a built-in type (checked before definer code casts keys); 40001 instead when the column is missing because the storage was made after the transaction''s snapshot (tgsis.chunk_snapshot_guard)';
