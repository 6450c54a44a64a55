-- tgsis.chunk_face_queue(): the row-level INSTEAD OF trigger of a chunk table's face (tgsis.create_chunk_face),
-- and its BEFORE statement trigger; TG_ARGV[0] the row table.
-- docs/storage.md, "The relational face over chunks": a write through the face is
-- written when its statement ends, by tgsis.chunk_face_write (the face's AFTER
-- statement trigger), which checks and writes all the statement's rows at once,
-- rewriting each touched chunk once. Per row this trigger only keeps the row: one
-- INSERT into the session's pg_temp.tgsis_face_rows_<view oid> (the operation,
-- the new and the old row; a DELETE's row read into pg_temp.tgsis_face_dels_<view
-- oid>), whose columns are of the face's own row type, each row numbered in the
-- statement's order (pg_temp.tgsis_face_seq: the flush needs the order of a
-- writable CTE's delete and insert of one key): the
-- rows are kept TYPED, never as text (a float's text form loses a NaN's payload
-- and, under the session's extra_float_digits, digits), so they are bit for bit
-- what the statement gave. It returns NEW (OLD for a DELETE), so RETURNING
-- and the row count are the statement's; a row the flush refuses fails the
-- whole statement (nothing written). A row a DELETE meets twice (a join
-- matching it twice) is kept and counted once, as a table deletes it once
-- (a unique index on the row's key in the table of deleted rows, its own so
-- that an INSERT's or UPDATE's row pays no index: each row's INSERT is dynamic
-- SQL, planned each time, and ON CONFLICT's planning was a third of a DELETE's
-- row; the face has one row per key, so a second row of one key is the same row).
-- BEFORE each INSERT/UPDATE/DELETE statement (TG_LEVEL = 'STATEMENT') it makes
-- the tables when the session has none and refuses (42501) one it did not make
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
    v_rows    text := format('pg_temp.%I', 'tgsis_face_rows_' || TG_RELID);
    v_dels    text := format('pg_temp.%I', 'tgsis_face_dels_' || TG_RELID);
    v_seq     text := 'pg_temp.tgsis_face_seq';  -- the order of the rows kept, across both tables and every face
    v_tab     text;
    v_keycols text[];
    v_n       bigint;
BEGIN
    IF TG_LEVEL = 'STATEMENT' THEN
        IF to_regclass(v_rows) IS NULL THEN
            EXECUTE format('CREATE TEMP TABLE %s (op "char" NOT NULL, n %s, o %s, s bigint NOT NULL) ON COMMIT DELETE ROWS',
                           v_rows, TG_RELID::regclass, TG_RELID::regclass);
        END IF;
        IF to_regclass(v_dels) IS NULL THEN
            EXECUTE format('CREATE TEMP TABLE %s (o %s NOT NULL, s bigint NOT NULL) ON COMMIT DELETE ROWS', v_dels, TG_RELID::regclass);
            -- the row key: the chunk table's key columns before revision, the chunk column in place of chunk
            SELECT array_agg(CASE WHEN a.attname = 'chunk' THEN r.chunkcolumn ELSE a.attname::text END ORDER BY a.attnum)
              INTO v_keycols
              FROM tgsis.chunk_registry(TG_ARGV[0]) r
              JOIN pg_attribute a ON a.attrelid = tgsis.chunk_relation(TG_ARGV[0], '_chunk')::regclass
             WHERE a.attnum > 0
               AND a.attnum < (SELECT b.attnum FROM pg_attribute b
                                WHERE b.attrelid = tgsis.chunk_relation(TG_ARGV[0], '_chunk')::regclass AND b.attname = 'revision');
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
        RETURN NULL;
    END IF;
    IF TG_OP = 'INSERT' THEN
        EXECUTE format('INSERT INTO %s VALUES (''I'', $1, NULL, nextval(%L))', v_rows, v_seq) USING NEW;
        RETURN NEW;
    ELSIF TG_OP = 'UPDATE' THEN
        EXECUTE format('INSERT INTO %s VALUES (''U'', $1, $2, nextval(%L))', v_rows, v_seq) USING NEW, OLD;
        RETURN NEW;
    END IF;
    EXECUTE format('INSERT INTO %s VALUES ($1, nextval(%L)) ON CONFLICT DO NOTHING', v_dels, v_seq) USING OLD;
    GET DIAGNOSTICS v_n = ROW_COUNT;
    IF v_n = 0 THEN
        -- met twice by the statement (DELETE ... USING a join): deleted and counted once, as on a table
        RETURN NULL;
    END IF;
    RETURN OLD;
END
$$;

REVOKE ALL ON FUNCTION tgsis.chunk_face_queue() FROM PUBLIC;

COMMENT ON FUNCTION tgsis.chunk_face_queue() IS
    'row-level INSTEAD OF trigger of the face of a chunk table (tgsis.create_chunk_face; TG_ARGV[0] the row table): keeps each row written, typed (the face''s row type, never text), in the session''s pg_temp.tgsis_face_rows_<view oid> (a DELETE''s in tgsis_face_dels_<view oid>, once) for tgsis.chunk_face_write, which checks and writes them when the statement ends; BEFORE each statement it makes those tables or refuses (42501) one the session made';
