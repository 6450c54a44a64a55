-- tgsis.chunk_face_queue(): the BEFORE statement trigger of a chunk table's face (tgsis.create_chunk_face);
-- TG_ARGV[0] the row table. The face's rows are kept by its own row function, generated with static SQL
-- by tgsis.create_chunk_face (<schema>.<table>_face_row: FOR EACH ROW, INSTEAD OF).
-- docs/storage.md, "The relational face over chunks": a write through the face is
-- written when its statement ends, by tgsis.chunk_face_write (the face's AFTER
-- statement trigger), which checks and writes all the statement's rows at once,
-- rewriting each touched chunk once. Per row the row function only keeps the row: one
-- INSERT into the session's table of rows (tgsis.chunk_face_work(table, 'rows'): the operation,
-- the new and the old row; a DELETE's row read into the table of deleted rows, kind 'dels'),
-- whose columns are of the face's own row type, each row numbered in the
-- statement's order (pg_temp.tgsis_face_seq: the flush needs the order of a
-- writable CTE's delete and insert of one key): the
-- rows are kept TYPED, never as text (a float's text form loses a NaN's payload
-- and, under the session's extra_float_digits, digits), so they are bit for bit
-- what the statement gave. It returns NEW (OLD for a DELETE), so RETURNING
-- and the row count are the statement's; a row the flush refuses fails the
-- whole statement (nothing written). A row a DELETE meets twice (a join
-- matching it twice) is kept and counted once, as a table deletes it once
-- (a unique index on the row's key in the table of deleted rows, its own so
-- that an INSERT's or UPDATE's row pays no index; the face has one row per key,
-- so a second row of one key is the same row).
-- A row of a key the statement deleted, or moved away, before (an earlier
-- writable WITH query) is skipped, counted 0, as the row view skips it: a
-- DELETE's by that unique index, an UPDATE's by one probe of it, made only
-- once the statement deletes or has kept rows before the sub-statement (the
-- setting tgsis.chunk_face_work(table, 'deleted'), which the flush clears); each
-- skipped row is kept as an event ('S', 'X') for the flush's order of the
-- statement's writes of the key.
-- BEFORE each INSERT/UPDATE/DELETE statement (TG_LEVEL = 'STATEMENT', here) it makes
-- the tables when the transaction has none (ON COMMIT DROP: made again by each
-- transaction that writes through the face, gone at its COMMIT or ROLLBACK, and
-- with a ROLLBACK TO a savepoint that made them; a later statement of the same
-- transaction finds them; so a session idle after it wrote holds nothing of the
-- face's row type, and add_property, the way back into rows and
-- alter_chunk_table do not wait for it: docs/storage.md; the sequence
-- tgsis_face_seq, which depends on nothing, lives as long as the session) and
-- refuses (42501) one it did not make
-- (another owner: a session's own table could carry its own rows or triggers,
-- run here with the definer's rights); a table made by the definer cannot be
-- dropped or replaced by the session afterwards, so checking once per
-- statement is enough for its rows.
-- The table is temporary: a transaction that wrote through a face cannot be
-- PREPAREd (two-phase commit refuses temporary objects; docs/storage.md).
-- SECURITY DEFINER: the table belongs to the storage's owner, whom the session
-- cannot impersonate.
CREATE FUNCTION tgsis.chunk_face_queue()
RETURNS trigger
LANGUAGE plpgsql
VOLATILE
SECURITY DEFINER
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_rows    text := tgsis.chunk_face_work(TG_ARGV[0], 'rows');
    v_dels    text := tgsis.chunk_face_work(TG_ARGV[0], 'dels');
    v_seq     text := 'pg_temp.tgsis_face_seq';  -- the order of the rows kept, across both tables and every face
    v_tab     text;
    v_keycols text[];
    v_flag    text := tgsis.chunk_face_work(TG_ARGV[0], 'deleted');  -- '1': the statement deletes (or moved away) keys
    v_pending boolean;
BEGIN
    IF TG_LEVEL = 'STATEMENT' THEN
        IF to_regclass(v_rows) IS NULL THEN
            EXECUTE format('CREATE TEMP TABLE %s (op "char" NOT NULL, n %s, o %s, s bigint NOT NULL) ON COMMIT DROP',
                           v_rows, TG_RELID::regclass, TG_RELID::regclass);
        END IF;
        IF to_regclass(v_dels) IS NULL THEN
            -- m: the old row of an UPDATE moving its key away (written by that UPDATE's row; here only so that a later
            -- sub-statement finds its key gone)
            EXECUTE format('CREATE TEMP TABLE %s (o %s NOT NULL, s bigint NOT NULL, m boolean NOT NULL DEFAULT false) '
                           'ON COMMIT DROP', v_dels, TG_RELID::regclass);
            -- the row key: the chunk table's key columns before revision, the chunk column in place of chunk
            v_keycols := tgsis.chunk_row_key(TG_ARGV[0]);
            -- a DELETE whose join meets a row twice deletes it once: the second a conflict on the row's key
            -- (a lookup before each insert was a sequential scan of the kept rows)
            EXECUTE format('CREATE UNIQUE INDEX ON %s (%s)', v_dels,
                           (SELECT string_agg(format('((o).%I)', k), ', ') FROM unnest(v_keycols) AS k));
        END IF;
        IF to_regclass(v_seq) IS NULL THEN
            CREATE TEMP SEQUENCE tgsis_face_seq;
        END IF;
        FOREACH v_tab IN ARRAY ARRAY[v_rows, v_dels, v_seq] LOOP
            IF (SELECT c.relowner FROM pg_class c WHERE c.oid = to_regclass(v_tab))
               <> (SELECT r.oid FROM pg_roles r WHERE r.rolname = current_user) THEN
                RAISE EXCEPTION 'the session''s table % was not made by the face''s trigger', v_tab
                    USING ERRCODE = 'insufficient_privilege', HINT = 'drop the temporary table and write again';
            END IF;
        END LOOP;
        -- the keys a statement deleted, or moved away, are gone for its later sub-statements (writable WITH
        -- queries; a statement nested in one), as the row view has them gone row by row (PostgreSQL's rule for a
        -- row changed by the same command: skipped): once a DELETE begins, or a sub-statement begins after others
        -- whose rows are kept, not yet written, the setting (tgsis.chunk_face_work(table, 'deleted')) tells the UPDATE rows to
        -- look their key up among the deleted rows (one index probe; a plain statement pays nothing per row), and
        -- the key moves of the UPDATE rows kept are added to them (set-based, once per sub-statement). PostgreSQL
        -- fires this trigger once per query for each of INSERT, UPDATE, DELETE: a second UPDATE sub-statement
        -- after one moving keys does not come here; the UPDATE row that moves a key marks it itself (the row function), so
        -- its later rows of that key are skipped all the same (docs/storage.md)
        EXECUTE format('SELECT EXISTS (SELECT FROM %s) OR EXISTS (SELECT FROM %s)', v_rows, v_dels) INTO v_pending;
        IF v_pending THEN
            v_keycols := tgsis.chunk_row_key(TG_ARGV[0]);
            EXECUTE format('INSERT INTO %s (o, s, m) SELECT r.o, r.s, true FROM %s r WHERE r.op = ''U'' AND NOT (%s) '
                           'ON CONFLICT DO NOTHING', v_dels, v_rows,
                           array_to_string(ARRAY(SELECT format('(r.n).%1$I IS NOT DISTINCT FROM (r.o).%1$I', k)
                                                   FROM unnest(v_keycols) AS k), ' AND '));
            EXECUTE format('SELECT EXISTS (SELECT FROM %s)', v_dels) INTO v_pending;
        END IF;
        IF v_pending OR TG_OP = 'DELETE' THEN
            PERFORM set_config(v_flag, '1', true);  -- (cleared by the flush)
        END IF;
        RETURN NULL;
    END IF;
    RAISE EXCEPTION 'tgsis.chunk_face_queue is the statement trigger of a face; its rows are kept by the face''s row function'
        USING ERRCODE = 'TG100', HINT = 'make the face with tgsis.create_chunk_face';
END
$$;

REVOKE ALL ON FUNCTION tgsis.chunk_face_queue() FROM PUBLIC;

COMMENT ON FUNCTION tgsis.chunk_face_queue() IS
    'BEFORE statement trigger of the face of a chunk table (tgsis.create_chunk_face; TG_ARGV[0] the row table): makes the transaction''s work tables (tgsis.chunk_face_work, ON COMMIT DROP) in which the face''s generated row function (<table>_face_row) keeps each row written, typed (the face''s row type, never text), for tgsis.chunk_face_write, which checks and writes them when the statement ends, or refuses (42501) one the session made; marks the keys a statement deleted or moved away for its later sub-statements';
