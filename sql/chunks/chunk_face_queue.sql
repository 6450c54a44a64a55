-- tgsis.chunk_face_queue(): the row-level INSTEAD OF trigger of a chunk table's face (tgsis.create_chunk_face),
-- and its BEFORE statement trigger.
-- docs/storage.md, "The relational face over chunks": a write through the face is
-- written when its statement ends, by tgsis.chunk_face_write (the face's AFTER
-- statement trigger), which checks and writes all the statement's rows at once,
-- rewriting each touched chunk once. Per row this trigger only keeps the row: one
-- static INSERT into the session's pg_temp.tgsis_face_rows (the face's oid, the
-- operation, the new and the old row as text), about 10 us a row where the
-- former per-row path spent 0.8 ms (catalog reads, dynamic SQL, a chunk rewrite
-- for each inserted or deleted row). The rows travel as text: composite output
-- with extra_float_digits pinned to 1 (shortest exact form of a double, -0 and
-- NaN included) read back by the flush in the same session, so they are bit for
-- bit what the statement gave. It returns NEW (OLD for a DELETE), so RETURNING
-- and the row count are the statement's; a row the flush refuses fails the
-- whole statement (nothing written). A row a DELETE meets twice (a join
-- matching it twice) is kept and counted once, as a table deletes it once.
-- BEFORE each INSERT/UPDATE/DELETE statement (TG_LEVEL = 'STATEMENT') it makes
-- the table when the session has none and refuses (42501) one it did not make
-- (another owner: a session's own table could carry its own rows or triggers,
-- run here with the definer's rights); a table made by the definer cannot be
-- dropped or replaced by the session afterwards, so checking once per
-- statement is enough for its rows.
-- SECURITY DEFINER: the table belongs to the storage's owner, whom the session
-- cannot impersonate.
CREATE FUNCTION tgsis.chunk_face_queue()
RETURNS trigger
LANGUAGE plpgsql
VOLATILE
SECURITY DEFINER
SET search_path = pg_catalog, pg_temp
SET extra_float_digits = 1  -- the rows as text: shortest exact doubles, whatever the session's setting
AS $$
DECLARE
    v_old text;
BEGIN
    IF TG_LEVEL = 'STATEMENT' THEN
        IF to_regclass('pg_temp.tgsis_face_rows') IS NULL THEN
            CREATE TEMP TABLE tgsis_face_rows (face oid NOT NULL, op "char" NOT NULL, newrow text, oldrow text)
                ON COMMIT DELETE ROWS;
            -- a DELETE whose join meets a row twice deletes it once: a unique index on the row read (its md5:
            -- any length of row), the second kept row a conflict, compared whole (a lookup before each insert
            -- was a sequential scan of the kept rows, 130 us a row for 10,000)
            CREATE UNIQUE INDEX tgsis_face_rows_deleted ON pg_temp.tgsis_face_rows (face, md5(oldrow)) WHERE op = 'D';
        ELSIF (SELECT c.relowner FROM pg_class c WHERE c.oid = to_regclass('pg_temp.tgsis_face_rows'))
              <> (SELECT r.oid FROM pg_roles r WHERE r.rolname = current_user) THEN
            RAISE EXCEPTION 'the session''s table pg_temp.tgsis_face_rows was not made by the face''s trigger'
                USING ERRCODE = 'insufficient_privilege', HINT = 'drop the temporary table and write again';
        END IF;
        RETURN NULL;
    END IF;
    IF TG_OP = 'INSERT' THEN
        INSERT INTO pg_temp.tgsis_face_rows VALUES (TG_RELID, 'I', NEW::text, NULL);
        RETURN NEW;
    ELSIF TG_OP = 'UPDATE' THEN
        INSERT INTO pg_temp.tgsis_face_rows VALUES (TG_RELID, 'U', NEW::text, OLD::text);
        RETURN NEW;
    END IF;
    v_old := OLD::text;
    INSERT INTO pg_temp.tgsis_face_rows VALUES (TG_RELID, 'D', NULL, v_old)
        ON CONFLICT (face, md5(oldrow)) WHERE op = 'D' DO NOTHING;
    IF NOT FOUND THEN
        -- met twice by the statement (DELETE ... USING a join): deleted and counted once, as on a table
        IF EXISTS (SELECT FROM pg_temp.tgsis_face_rows r
                    WHERE r.face = TG_RELID AND r.op = 'D' AND md5(r.oldrow) = md5(v_old) AND r.oldrow = v_old) THEN
            RETURN NULL;
        END IF;
        -- two different rows of one md5: never taken for one
        RAISE EXCEPTION 'two rows deleted from % by one statement have the same md5', TG_TABLE_NAME
            USING ERRCODE = 'TG100', DETAIL = 'The face keeps the rows a DELETE meets by the md5 of their text.',
                  HINT = 'delete these rows in two statements';
    END IF;
    RETURN OLD;
END
$$;

REVOKE ALL ON FUNCTION tgsis.chunk_face_queue() FROM PUBLIC;

COMMENT ON FUNCTION tgsis.chunk_face_queue() IS
    'row-level INSTEAD OF trigger of the face of a chunk table (tgsis.create_chunk_face): keeps each row written (as text, exact) in the session''s pg_temp.tgsis_face_rows for tgsis.chunk_face_write, which checks and writes them when the statement ends; BEFORE each statement it makes that table or refuses (42501) one the session made';
