-- tgsis.update_shared_rows(table, set, condition, $1, $2, $3, $4): UPDATE rows other versions' writers may hold, never waiting while holding some; returns the rows updated.
-- A stored row of a version is shared by every version that sees it: the
-- children of a parent all see its rows, and writers in each of them close
-- those rows (append to lastrevs) in their own revisions, row by row in the
-- order of their statements. Merge, refresh and delete_version change such
-- rows for many at once, locking only the versions they involve. Had their
-- UPDATE waited for one row while holding others, a writer elsewhere wanting
-- one of those would deadlock with it (40P01; tests/test_concurrency.py). So
-- the UPDATE never waits (a 1 ms lock_timeout undoes it as a whole), and
-- when a row is taken, its holder is waited for with no row lock held (under
-- the caller's lock_timeout), then the UPDATE is tried again.
-- p_set and p_where are SQL over the alias v of the table's storage and the
-- parameters $1 text[], $2 integer[], $3 integer[], $4 integer; every
-- statement runs through tgsis.storage_run (as the storage's owner).
CREATE FUNCTION tgsis.update_shared_rows(
    p_t     tgsis.versioned_tables,
    p_set   text,
    p_where text,
    p_1     text[],
    p_2     integer[],
    p_3     integer[],
    p_4     integer)
RETURNS bigint
LANGUAGE plpgsql
VOLATILE
AS $$
DECLARE
    v_table   text := tgsis.storage_table(p_t.schemaname, p_t.tablename);  -- <table>_ver, or tgsis.<table>_chunk
    v_count   bigint;
    v_busy    text[];
    v_timeout text := current_setting('lock_timeout');
    v_undo    CONSTANT text := 'tgsis: undo the row locks of this block';
BEGIN
    LOOP
        BEGIN
            PERFORM set_config('lock_timeout', '1ms', true);
            SELECT r[1]::bigint INTO v_count
              FROM tgsis.storage_run(p_t, true, format('UPDATE %s v SET %s WHERE %s', v_table, p_set, p_where),
                                     p_1, p_2, p_3, p_4) AS r;
            PERFORM set_config('lock_timeout', v_timeout, true);
            RETURN v_count;
        EXCEPTION WHEN lock_not_available THEN
            NULL;   -- the block's row locks, changes and setting are undone
        END;
        -- a row another transaction holds: one the UPDATE would change that
        -- cannot be locked now (found in a block then undone: none stays locked)
        v_busy := NULL;
        BEGIN
            -- (a row's place is (tableoid, ctid): partitioned storage is many tables)
            SELECT r INTO v_busy
              FROM tgsis.storage_run(p_t, false, format(
                       'SELECT ARRAY[b.tableoid::text, b.ctid::text]
                          FROM (SELECT v.tableoid, v.ctid FROM %1$s v WHERE %2$s EXCEPT
                                SELECT f.tableoid, f.ctid FROM (SELECT v.tableoid, v.ctid FROM %1$s v WHERE %2$s
                                                                 FOR UPDATE SKIP LOCKED) f
                                LIMIT 1) b', v_table, p_where), p_1, p_2, p_3, p_4) AS r;
            RAISE EXCEPTION USING MESSAGE = v_undo;
        EXCEPTION WHEN OTHERS THEN
            IF SQLERRM IS DISTINCT FROM v_undo THEN
                RAISE;
            END IF;
        END;
        IF v_busy IS NOT NULL THEN
            -- wait for its holder, then let go of the row again
            BEGIN
                PERFORM FROM tgsis.storage_run(p_t, false, format(
                    'SELECT ARRAY[]::text[] FROM %s v WHERE v.tableoid = ($1[1])::oid AND v.ctid = ($1[2])::tid FOR UPDATE',
                    v_table), v_busy);
                RAISE EXCEPTION USING MESSAGE = v_undo;
            EXCEPTION WHEN OTHERS THEN
                IF SQLERRM IS DISTINCT FROM v_undo THEN
                    RAISE;
                END IF;
            END;
        END IF;
    END LOOP;
END
$$;

COMMENT ON FUNCTION tgsis.update_shared_rows(tgsis.versioned_tables, text, text, text[], integer[], integer[], integer) IS
    'UPDATE <table>_ver v SET p_set WHERE p_where ($1..$4 = p_1..p_4) without ever waiting for a row while holding others, so that it cannot deadlock with writers of other versions that see the same stored rows; returns the rows updated';
