-- tgsis.chunk_face_write(): the AFTER statement trigger of a chunk table's face (tgsis.create_chunk_face), TG_ARGV[0] the row table.
-- Writes on the face (INSERT, UPDATE, DELETE) are kept row by row by the face's
-- INSTEAD OF row trigger (its generated <table>_face_row) and written here when the
-- statement ends, all at once: one rewrite per touched chunk per statement,
-- into tgsis.<table>_chunk through the one writer of chunk contents,
-- tgsis.write_chunk_rows, keeping the guarantees of today's versioned views'
-- triggers (tgsis.versioning_trigger_source) for every row:
--   * the rights: the class's write right on each object (tgsis.check_class_write,
--     as the storage's owner writes for the caller), the write right on the
--     session's version and TG301 while an older revision is viewed
--     (tgsis.write_revision; and the statement check tgsis.view_write_check),
--     TG305 for unversioned storage outside DEFAULT's working revision
--     (tgsis.plain_write_check), features of classes without versioning in
--     revision 0 (tgsis.unversioned_revision); object locks (TG3xx by
--     tgsis.check_objects_unlocked); the object's write lock shared
--     (tgsis.object_lock_key), so that bulk writers, which take it
--     exclusively, never decide from a state a face write is changing; the
--     note of the changed object (tgsis.record_changed_objects, never for
--     revision 0);
--   * no lost update (docs/versioning.md): a face writer takes the chunk's
--     transaction lock (an advisory lock per table, object, chunk and version,
--     exclusive, in key order), then reads the chunk's visible version with a
--     new snapshot (READ COMMITTED: what a writer it waited for committed;
--     REPEATABLE READ and SERIALIZABLE keep the transaction's, and a chunk
--     changed after it is 40001 from tgsis.write_chunk_rows' lock or insert)
--     and compares the slot it writes with the row the statement read
--     (binary equality, *=): changed meanwhile is 40001, changed by this
--     transaction since the statement read it is 27000 (deleted by it, too: a
--     retry would fail again), deleted meanwhile is 40001 too (an UPDATE's, a
--     DELETE's: the statement has counted and returned the row already, so
--     skipping it as a plain table does would make its count wrong). Other slots
--     keep what concurrent writers committed: the writer merges into the
--     current chunk. Two face writers of different slots of one chunk wait
--     for each other (the lock is the chunk's), and two chunks locked in
--     opposite orders can deadlock (40P01) where rows would not;
--   * INSERT of a visible key is 23505 naming today's key (<table>_pkey), TG306
--     when the client's query says ON CONFLICT (as today's views); a key
--     inserted twice by one statement is 23505 too; an UPDATE changing the
--     key is a delete of the old key and an insert of the new (23505 when it
--     is there, also when the statement moves another row away from it: a
--     plain table's key is checked row by row as well); RETURNING returns the
--     row given (the row function's NEW or OLD);
--   * the statement's rows, moved from the work tables of rows and deleted rows
--     (tgsis.chunk_face_work; kept typed, the face's row type, by the face's
--     generated row function) into the face's
--     queue (tgsis.chunk_face_work(table, 'queue'): the transaction's, ON COMMIT
--     DROP as the row trigger's tables, owned by the storage's owner), are
--     checked and written all at once:
--     the chunks they touch locked in key order, compared set-based, written
--     by one call of tgsis.write_chunk_rows (a key twice in one statement,
--     not two inserts: 21000); a statement changing features of versioned
--     classes and of classes without versioning (which no row leaves: each
--     keeps its key) is written in two groups, the latter in revision 0
--     (through the work table 'now'), as today's view writes row
--     by row (one group's revision for both was TG300).
-- (A write whose snapshot predates the chunk table's last rewrite, which such
-- a snapshot sees empty, is refused before, by the face's statement trigger
-- tgsis.chunk_snapshot_check.)
-- A chunk's lock is named by its key as text (a double key, model 2's times,
-- printed exactly whatever the session's extra_float_digits: pinned here, so
-- that two sessions name one chunk alike).
-- The temporary tables are refused (42501) when the session made them itself
-- (another owner): rows written here come only from the face's own rows.
-- SECURITY DEFINER: it writes the chunk table as its owner.
CREATE FUNCTION tgsis.chunk_face_write()
RETURNS trigger
LANGUAGE plpgsql
VOLATILE
SECURITY DEFINER
SET search_path = pg_catalog, pg_temp
SET extra_float_digits = 1  -- the chunks' locks name a double key (times) as text: every session alike, exactly
AS $$
DECLARE
    v_table     text := TG_ARGV[0];
    v_reg       record;
    v_objclass  text;      -- the object class the object locks name: the model table's, 'feature' for a class's table
    v_sch       text;      -- the table's schema and name, for the messages and the notes
    v_tname     text;
    v_face      text := format('%I.%I', TG_TABLE_SCHEMA, TG_TABLE_NAME);
    v_chunk     text;
    v_now       text := tgsis.chunk_face_work(v_table, 'now');
    v_queue     text := tgsis.chunk_face_work(v_table, 'queue');
    v_rows      text := tgsis.chunk_face_work(v_table, 'rows');  -- the statement's rows (the face's row function)
    v_dels      text := tgsis.chunk_face_work(v_table, 'dels');  -- its DELETE's rows read
    v_kc        text;      -- the object key column (geoid)
    v_cc        text;      -- the chunk column (the local id)
    v_keycols   text[];    -- the row key: the key columns, then the chunk column
    v_shift     integer;
    v_keys      text[];    -- the object keys written, as text
    v_geoids    bigint[];
    v_vid       integer;
    v_w         integer;
    v_set       integer[];
    v_vis       text := '(c.revision = ANY ($1)) IS TRUE AND NOT (c.lastrevs && $1)';
    v_match     text;      -- the chunk version of the row %1$s: key and chunk
    v_keytext   text;
    v_state     text;      -- of the row's slot now: absent, same, changed, mine (changed by this transaction)
    v_chunks    text[];
    v_count     bigint;
    v_distinct  bigint;
    v_gone      text;
    v_changed   text;
    v_mine      boolean;
    v_pair      bigint[];  -- an UPDATE's new and old object key, when they differ
    v_dupkey    text;      -- an inserted row's key that is there
    v_dec       record;    -- tgsis.chunk_decode_sql's pieces, the chunk table's alias c
    v_deletes   boolean;   -- the statement's rows delete some (the right checked: UPDATE, DELETE)
    v_tab       text;
    v_split     boolean;   -- the flush's second group (features of classes without versioning) waits in v_now
    v_moved     bigint;
    v_ev        record;    -- a key the statement wrote more than once: its events in order
    v_code      text;
    v_err       text;      -- the first refusal in the statement's order, its place and key
    v_errat     bigint;
    v_errkey    text;
    v_at        bigint;
    v_st        text;
    v_nu        integer;
    v_i         integer;
    v_any       boolean;   -- the statement kept rows in v_rows (not only deleted rows)
    v_multi     boolean;   -- some key has more than one event in the statement
BEGIN
    SELECT * INTO v_reg FROM tgsis.chunk_registry(v_table) r;
    v_objclass := coalesce((SELECT t.objectclass FROM tgsis.model_tables t WHERE t.tablename = v_reg.tablename AND v_reg.classname IS NULL),
                           'feature');
    v_sch := v_reg.schemaname;
    v_tname := v_reg.tablename;
    v_chunk := tgsis.chunk_relation(v_table, '_chunk');
    v_kc := v_reg.keycolumn;
    v_cc := v_reg.chunkcolumn;
    v_shift := round(log(2, v_reg.chunksize))::integer;
    -- the row key: the chunk table's key columns before revision, the chunk column last (in place of chunk),
    -- from the catalog in one query: the queued path of an UPDATE needs nothing more
    SELECT array_agg(CASE WHEN a.attname = 'chunk' THEN v_cc ELSE a.attname::text END ORDER BY a.attnum) INTO v_keycols
      FROM pg_attribute a
     WHERE a.attrelid = v_chunk::regclass AND a.attnum > 0
       AND a.attnum < (SELECT r.attnum FROM pg_attribute r WHERE r.attrelid = v_chunk::regclass AND r.attname = 'revision');
    IF TG_LEVEL = 'ROW' THEN
        RAISE EXCEPTION 'tgsis.chunk_face_write is the statement trigger of a face; its rows are kept by the face''s row function'
            USING ERRCODE = 'TG100', HINT = 'make the face with tgsis.create_chunk_face';
    END IF;
    -- the pieces of the statements below, for a row %1$s of the face's type (the queue's q): its chunk's version c,
    -- the chunk versions decoded, the key as text
    v_match := array_to_string(ARRAY(SELECT format('c.%I = (%%1$s).%I', k, k) FROM unnest(v_keycols[1:cardinality(v_keycols) - 1]) AS k)
                               || format('c.chunk = (%%1$s).%I >> %s', v_cc, v_shift), ' AND ');
    SELECT * INTO v_dec FROM tgsis.chunk_decode_sql(v_table, 'c') AS d;
    v_keytext := format('concat_ws(%L, %s)', ', ',
                        (SELECT string_agg(format('(%%1$s).%I::text', k), ', ' ORDER BY o) FROM unnest(v_keycols) WITH ORDINALITY AS u(k, o)));
    -- the transaction's temporary tables of rows to write (ON COMMIT DROP: a session idle after its commit keeps
    -- nothing of the face's row type): the face's columns, _delete, the row read; v_now only when a statement
    -- may be split in two groups (below: only while some feature is of a class without versioning; a table
    -- made per transaction costs 2-5 ms)
    FOREACH v_tab IN ARRAY ARRAY[v_queue] LOOP
        IF to_regclass(v_tab) IS NULL THEN
            EXECUTE format('CREATE TEMP TABLE %s (LIKE %s, _delete boolean NOT NULL DEFAULT false, tgsis_old %s, tgsis_seq bigint) '
                           'ON COMMIT DROP', v_tab, v_face, v_face);
        ELSIF (SELECT c.relowner FROM pg_class c WHERE c.oid = to_regclass(v_tab)) <> (SELECT r.oid FROM pg_roles r WHERE r.rolname = current_user) THEN
            RAISE EXCEPTION 'the session''s table % was not made by the face''s trigger', v_tab
                USING ERRCODE = 'insufficient_privilege', HINT = 'drop the temporary table and write again';
        END IF;
    END LOOP;


    -- the statement's rows kept by the face's row function (its table checked before the statement), as the
    -- face's rows: an INSERT's row, a DELETE's (the row read), an UPDATE keeping the key (the new row and the
    -- row read); an UPDATE changing the key is a delete of the row read and an insert of the new row
    IF to_regclass(v_rows) IS NULL OR to_regclass(v_dels) IS NULL THEN
        RETURN NULL;
    END IF;
    FOREACH v_tab IN ARRAY ARRAY[v_rows, v_dels] LOOP
        IF (SELECT c.relowner FROM pg_class c WHERE c.oid = to_regclass(v_tab)) <> (SELECT r.oid FROM pg_roles r WHERE r.rolname = current_user) THEN
            RAISE EXCEPTION 'the session''s table % was not made by the face''s trigger', v_tab
                USING ERRCODE = 'insufficient_privilege', HINT = 'drop the temporary table and write again';
        END IF;
    END LOOP;
    -- an UPDATE moving rows between a feature of a class without versioning and a versioned feature: TG300
    -- (tgsis.unversioned_revision), as today's view refuses it, never two writes in two revisions
    IF v_objclass = 'feature' AND EXISTS (SELECT FROM tgsis.unversioned_features) THEN
        FOR v_pair IN EXECUTE format('SELECT DISTINCT ARRAY[(r.n).%2$I, (r.o).%2$I]::bigint[] '
                                     '  FROM %1$s r WHERE r.op = ''U'' '
                                     '   AND (r.n).%2$I IS DISTINCT FROM (r.o).%2$I', v_rows, v_kc) LOOP
            IF EXISTS (SELECT FROM tgsis.unversioned_features u WHERE u.geoid = ANY (v_pair)) THEN
                PERFORM tgsis.unversioned_revision(v_pair);  -- TG300 when one of the two is versioned
            END IF;
        END LOOP;
    END IF;
    -- the statement's writes of one key more than once, in its order (writable WITH queries: every
    -- sub-statement's rows reach this flush together), answered as the row view answers them row by row:
    -- events i (an inserted row, also an UPDATE's new key), u (an UPDATE keeping the key), d (a deleted row),
    -- m (an UPDATE's old key when it moves), S and X (an UPDATE, a DELETE the row trigger skipped, counted 0,
    -- since the statement had deleted the row, or moved it away, before). A key whose first event is not i was there when the
    -- statement began (it read the row); its state walks orig -> changed (u) or gone (d), moved (m) -> new (i):
    --   i of a key there (orig, changed, new) is 23505; u or d (X) of a row changed or inserted again since the
    --   statement read it is 27000; two UPDATEs of one row (u or S, an UPDATE ... FROM meeting it twice, two WITH
    --   queries; also when the row was deleted before, not when it was moved away: skipped however often, as
    --   the row view skips it) are 21000, which the row view raises when the statement
    --   ends, so after any of the others; a key whose first event is i and that has others: 23505 (there
    --   already, or inserted twice). The first refusal in the statement's order is raised; nothing is written.
    -- A statement that only deleted (no row kept in v_rows) has one event per key (the table of deleted rows has a
    -- unique index on the row key): nothing to walk, and the query is skipped. When no key has two events, the
    -- queue below holds each key once (its rows are the events but the skipped S and X), and its count of
    -- distinct keys is skipped too (v_multi false).
    v_err := NULL;
    v_multi := false;
    EXECUTE format('SELECT EXISTS (SELECT FROM %s)', v_rows) INTO v_any;
    IF v_any THEN
    FOR v_ev IN EXECUTE format(
            'WITH e AS (SELECT %3$s AS kt, lower(r.op::text) AS ev, r.s FROM %1$s r WHERE r.op IN (''I'') '
            '           UNION ALL SELECT %4$s, CASE WHEN r.op = ''U'' AND NOT (%5$s) THEN ''m'' WHEN r.op = ''U'' THEN ''u'' '
            '                                     ELSE r.op::text END, r.s FROM %1$s r WHERE r.op IN (''U'', ''S'', ''X'') '
            '           UNION ALL SELECT %3$s, ''i'', r.s FROM %1$s r WHERE r.op = ''U'' AND NOT (%5$s) '
            '           UNION ALL SELECT %6$s, ''d'', d.s FROM %2$s d WHERE NOT d.m) '
            'SELECT e.kt, array_agg(e.ev ORDER BY e.s, e.ev = ''i'') AS evs, array_agg(e.s ORDER BY e.s, e.ev = ''i'') AS ss '
            '  FROM e GROUP BY e.kt HAVING count(*) > 1',
            v_rows, v_dels, format(v_keytext, 'r.n'), format(v_keytext, 'r.o'),
            array_to_string(ARRAY(SELECT format('(r.n).%1$I IS NOT DISTINCT FROM (r.o).%1$I', k) FROM unnest(v_keycols) AS k), ' AND '),
            format(v_keytext, 'd.o')) LOOP
        v_multi := true;
        v_code := NULL;
        IF v_ev.evs[1] = 'i' THEN
            v_code := '23505';
            v_at := CASE WHEN v_ev.evs <> array_fill('i'::text, ARRAY[cardinality(v_ev.evs)]) THEN v_ev.ss[1] ELSE v_ev.ss[2] END;
        ELSE
            v_st := 'orig';
            v_nu := 0;
            FOR v_i IN 1 .. cardinality(v_ev.evs) LOOP
                v_at := v_ev.ss[v_i];
                CASE v_ev.evs[v_i]
                    -- (u or d of a key gone: only if the row trigger missed the statement's delete, a setting the
                    -- session changed in between; refused, never written twice)
                    WHEN 'u' THEN
                        v_nu := v_nu + 1;
                        IF v_st IN ('new', 'gone', 'moved') THEN v_code := '27000'; ELSE v_st := 'changed'; END IF;
                    WHEN 'S' THEN
                        -- (a row moved away is skipped however often it is met again, as the row view skips it)
                        IF v_st <> 'moved' THEN v_nu := v_nu + 1; END IF;
                        IF v_st = 'new' THEN v_code := '27000'; END IF;
                    WHEN 'd' THEN
                        IF v_st <> 'orig' THEN v_code := '27000'; ELSE v_st := 'gone'; END IF;
                    WHEN 'm' THEN
                        IF v_st <> 'orig' THEN v_code := '27000'; ELSE v_st := 'moved'; END IF;
                    WHEN 'X' THEN
                        IF v_st IN ('changed', 'new') THEN v_code := '27000'; ELSIF v_st <> 'moved' THEN v_st := 'gone'; END IF;
                    ELSE  -- 'i'
                        IF v_st NOT IN ('gone', 'moved') THEN v_code := '23505'; ELSE v_st := 'new'; END IF;
                END CASE;
                EXIT WHEN v_code IS NOT NULL;
            END LOOP;
            IF v_code IS NULL AND v_nu > 1 THEN
                v_code := '21000';
                v_at := NULL;  -- when the statement ends
            END IF;
        END IF;
        IF v_code IS NOT NULL AND (v_err IS NULL OR (v_err = '21000' AND v_code <> '21000') OR v_at < v_errat) THEN
            v_err := v_code;
            v_errat := v_at;
            v_errkey := v_ev.kt;
        END IF;
    END LOOP;
    END IF;
    IF v_err = '21000' THEN
        RAISE EXCEPTION 'one statement changed a row of %.% twice', TG_TABLE_SCHEMA, TG_TABLE_NAME
            USING ERRCODE = 'cardinality_violation', DETAIL = format('Row (%s)=(%s).', array_to_string(v_keycols, ', '), v_errkey),
                  HINT = 'change each row of a versioned view once in a statement';
    ELSIF v_err = '27000' THEN
        RAISE EXCEPTION 'a row (%)=(%) of %.% to be changed was already changed by the current statement',
                array_to_string(v_keycols, ', '), v_errkey, v_sch, v_tname
            USING ERRCODE = 'triggered_data_change_violation',
                  DETAIL = 'The statement (its writable WITH queries) changes or deletes a row it changed, deleted or inserted again before.',
                  HINT = 'Change each row of a versioned view once in a statement.',
                  TABLE = v_tname, SCHEMA = v_sch;
    ELSIF v_err = '23505' THEN
        RAISE EXCEPTION 'duplicate key value violates unique constraint "%"', v_tname || '_pkey'
            USING ERRCODE = 'unique_violation',
                  DETAIL = format('Key (%s)=(%s) is there when the statement inserts it in version %s.',
                                  array_to_string(v_keycols, ', '), v_errkey, quote_literal(tgsis.get_working_version())),
                  CONSTRAINT = v_tname || '_pkey', TABLE = v_tname, SCHEMA = v_sch;
    END IF;
    PERFORM set_config(tgsis.chunk_face_work(v_table, 'deleted'), '', true);
    -- the kept rows, typed (the face's row type: bit for bit), moved into the queue (the skipped ones, S and X,
    -- and the old rows of moved keys, which the UPDATE's own row writes, only served the order above)
    EXECUTE format('WITH r AS (DELETE FROM %1$s r RETURNING r.op, r.n, r.o, r.s), '
                   '     d AS (DELETE FROM %4$s d WHERE NOT d.m RETURNING d.o, d.s), '
                   '     kept AS (SELECT r.op, r.n, r.o, r.s FROM r UNION ALL SELECT ''D''::"char", NULL::%5$s, d.o, d.s FROM d), '
                   '     k AS (SELECT kept.*, kept.op = ''U'' AND %3$s AS same FROM kept) '
                   'INSERT INTO %2$s SELECT (x.r).*, x.del, x.old, x.s FROM ('
                   '  SELECT k.n AS r, false AS del, CASE WHEN k.same THEN k.o END AS old, k.s FROM k WHERE k.op IN (''I'', ''U'') '
                   '  UNION ALL SELECT k.o, true, k.o, k.s FROM k WHERE k.op = ''D'' OR (k.op = ''U'' AND NOT k.same)) x',
                   v_rows, v_queue,
                   array_to_string(ARRAY(SELECT format('(kept.n).%1$I IS NOT DISTINCT FROM (kept.o).%1$I', k)
                                           FROM unnest(v_keycols) AS k), ' AND '),
                   v_dels, v_face);
    EXECUTE format('DELETE FROM %s', v_dels);

    <<groups>>
    LOOP
    IF TG_LEVEL = 'STATEMENT' AND v_split IS NULL THEN
        -- features of classes without versioning are written in revision 0, the others in the working revision:
        -- when the statement changed both, those of no version wait in v_now (empty between rows) for a second pass
        v_split := false;
        IF v_objclass = 'feature'
           AND EXISTS (SELECT FROM tgsis.versioned_tables t WHERE t.schemaname = v_sch AND t.tablename = v_tname)
           AND EXISTS (SELECT FROM tgsis.unversioned_features) THEN
            IF to_regclass(v_now) IS NULL THEN
                EXECUTE format('CREATE TEMP TABLE %s (LIKE %s, _delete boolean NOT NULL DEFAULT false, tgsis_old %s, tgsis_seq bigint) '
                               'ON COMMIT DROP', v_now, v_face, v_face);
            ELSIF (SELECT c.relowner FROM pg_class c WHERE c.oid = to_regclass(v_now)) <> (SELECT r.oid FROM pg_roles r WHERE r.rolname = current_user) THEN
                RAISE EXCEPTION 'the session''s table % was not made by the face''s trigger', v_now
                    USING ERRCODE = 'insufficient_privilege', HINT = 'drop the temporary table and write again';
            END IF;
            EXECUTE format('WITH moved AS (DELETE FROM %1$s q WHERE q.%3$I IN (SELECT u.geoid FROM tgsis.unversioned_features u) '
                           '  AND EXISTS (SELECT FROM %1$s o WHERE o.%3$I NOT IN (SELECT u.geoid FROM tgsis.unversioned_features u)) '
                           'RETURNING q.*) INSERT INTO %2$s SELECT * FROM moved', v_queue, v_now, v_kc);
            GET DIAGNOSTICS v_moved = ROW_COUNT;
            v_split := v_moved > 0;
        END IF;
    END IF;
    IF TG_LEVEL = 'STATEMENT' THEN
        -- the end of an UPDATE: every queued row of the face at once (of one group)
        -- (the object keys: distinct by hashing, the few left sorted, as array_agg(DISTINCT) sorted every row)
        EXECUTE format('SELECT count(*), %s, (SELECT array_agg(o.k ORDER BY o.k) FROM (SELECT DISTINCT q.%I::text AS k FROM %s q) o), '
                       'coalesce(bool_or(q._delete), false) FROM %s q',
                       CASE WHEN v_multi
                            THEN format('count(DISTINCT (%s))',
                                        array_to_string(ARRAY(SELECT format('q.%I', k) FROM unnest(v_keycols) AS k), ', '))
                            ELSE 'count(*)' END,
                       v_kc, v_queue, v_queue)
           INTO v_count, v_distinct, v_keys, v_deletes;
        IF v_count = 0 THEN
            RETURN NULL;
        END IF;
        IF v_distinct <> v_count THEN
            -- a key met more than once by the statement (writable CTEs: every sub-statement's rows reach this flush
            -- together), its rows in the statement's order (tgsis_seq; an UPDATE changing the key deletes the old
            -- key before it inserts the new): i an inserted row, d a deleted one, u one updated in place. Row by row,
            -- as the row view answers: a key deleted then inserted is one write of its slot, compared with the
            -- row the delete read; a row updated twice (an UPDATE ... FROM joining it twice, two WITH queries) is
            -- 21000; a row deleted after the statement changed it, or changed after it deleted it, is 27000;
            -- any other repetition inserts a key that is there (inserted twice, inserted before the statement
            -- deletes or moves the row holding it, inserted after an update kept it): 23505
            EXECUTE format('WITH e AS (SELECT %1$s AS kt, CASE WHEN q._delete THEN ''d'' WHEN q.tgsis_old IS NULL THEN ''i'' ELSE ''u'' END AS ev, '
                           '                  q.tgsis_seq AS s, q._delete AS del FROM %2$s q), '
                           '     g AS (SELECT e.kt, array_agg(e.ev ORDER BY e.s, e.del DESC) AS evs FROM e GROUP BY e.kt HAVING count(*) > 1) '
                           'SELECT (array_agg(g.kt) FILTER (WHERE cardinality(array_positions(g.evs, ''d'')) '
                           '                                     + cardinality(array_positions(g.evs, ''u'')) > 1))[1], '
                           '       (array_agg(g.kt) FILTER (WHERE g.evs <> ARRAY[''d'', ''i'']))[1], '
                           '       (array_agg(g.kt) FILTER (WHERE cardinality(array_positions(g.evs, ''u'')) = cardinality(g.evs)))[1] '
                           '  FROM g',
                           format(v_keytext, 'q'), v_queue)
               INTO v_changed, v_dupkey, v_gone;
            IF v_gone IS NOT NULL THEN
                RAISE EXCEPTION 'one statement changed a row of %.% twice', TG_TABLE_SCHEMA, TG_TABLE_NAME
                    USING ERRCODE = 'cardinality_violation', DETAIL = format('Row (%s)=(%s).', array_to_string(v_keycols, ', '), v_gone),
                          HINT = 'change each row of a versioned view once in a statement';
            END IF;
            IF v_changed IS NOT NULL THEN
                RAISE EXCEPTION 'a row (%)=(%) of %.% to be changed was already changed by the current statement',
                        array_to_string(v_keycols, ', '), v_changed, v_sch, v_tname
                    USING ERRCODE = 'triggered_data_change_violation',
                          DETAIL = 'The statement (its writable WITH queries) changes or deletes one row twice.',
                          HINT = 'Change each row of a versioned view once in a statement.',
                          TABLE = v_tname, SCHEMA = v_sch;
            END IF;
            IF v_dupkey IS NOT NULL THEN
                RAISE EXCEPTION 'duplicate key value violates unique constraint "%"', v_tname || '_pkey'
                    USING ERRCODE = 'unique_violation',
                          DETAIL = format('Key (%s)=(%s) is there when the statement inserts it in version %s.',
                                          array_to_string(v_keycols, ', '), v_dupkey, quote_literal(tgsis.get_working_version())),
                          CONSTRAINT = v_tname || '_pkey', TABLE = v_tname, SCHEMA = v_sch;
            END IF;
            -- each key deleted then inserted: the insert's row writes the slot, compared with the row the delete read
            EXECUTE format('WITH dd AS (DELETE FROM %1$s q WHERE q._delete AND EXISTS ('
                           '               SELECT FROM %1$s i WHERE NOT i._delete AND i.tgsis_old IS NULL AND %2$s) '
                           '             RETURNING q.*) '
                           'UPDATE %1$s i SET tgsis_old = dd.tgsis_old FROM dd '
                           ' WHERE NOT i._delete AND i.tgsis_old IS NULL AND %3$s',
                           v_queue,
                           array_to_string(ARRAY(SELECT format('i.%1$I = q.%1$I', k) FROM unnest(v_keycols) AS k), ' AND '),
                           array_to_string(ARRAY(SELECT format('i.%1$I = dd.%1$I', k) FROM unnest(v_keycols) AS k), ' AND '));
        END IF;
    END IF;
    v_geoids := v_keys::bigint[];

    -- rights, revision, object locks, notes (per row; for the queued rows, by the flush for all at once)
    -- (a class's own table: the face's grants, the class table's, were checked by PostgreSQL for the statement)
    IF v_reg.classname IS NULL THEN
        PERFORM tgsis.check_class_write(v_geoids, CASE WHEN v_deletes THEN 'UPDATE, DELETE' ELSE 'UPDATE' END);
    END IF;
    IF EXISTS (SELECT FROM tgsis.versioned_tables t WHERE t.schemaname = v_sch AND t.tablename = v_tname) THEN
        SELECT w.versionid, w.revision, w.revisions INTO v_vid, v_w, v_set FROM tgsis.write_revision() AS w;  -- TG002, TG301
        IF v_objclass = 'feature' AND EXISTS (SELECT FROM tgsis.unversioned_features u WHERE u.geoid = ANY (v_geoids)) THEN
            v_w := tgsis.unversioned_revision(v_geoids);  -- TG305, TG300
            v_set := ARRAY[0];
        END IF;
    ELSE
        PERFORM tgsis.plain_write_check(v_sch, v_tname);  -- TG305
        v_vid := tgsis.version_id(tgsis.get_working_version());
        v_w := 0;
        v_set := ARRAY[0];
    END IF;
    IF EXISTS (SELECT FROM tgsis.object_locks l WHERE l.objectclass = v_objclass AND l.objectkey = ANY (v_keys)) THEN
        PERFORM tgsis.check_objects_unlocked(v_objclass, v_keys);
    END IF;
    IF cardinality(v_keys) > tgsis.object_lock_limit() THEN
        -- more objects than the shared lock table holds locks for: the class's lock in the version, exclusively
        PERFORM pg_advisory_xact_lock(tgsis.object_class_lock_key(v_objclass, v_vid));
    ELSE
        PERFORM pg_advisory_xact_lock_shared(tgsis.object_lock_key(v_objclass, k, v_vid))
           FROM (SELECT DISTINCT k FROM unnest(v_keys) AS k ORDER BY k) AS s;
    END IF;
    IF v_w <> 0 AND EXISTS (SELECT FROM unnest(v_keys) AS k
                             WHERE NOT EXISTS (SELECT FROM tgsis.revision_objects o
                                                WHERE o.revision = v_w AND o.schemaname = v_sch AND o.tablename = v_tname
                                                  AND o.objectkey = k)) THEN
        PERFORM tgsis.record_changed_objects(v_sch, v_tname, v_keys);
    END IF;

    IF TG_LEVEL = 'STATEMENT' THEN
        -- the chunks' locks in key order, then the queued slots compared with what the statement read
        EXECUTE format('SELECT array_agg(DISTINCT ROW(%s)::text) FROM %s q',
                       array_to_string(ARRAY(SELECT format('q.%I', k) FROM unnest(v_keycols[1:cardinality(v_keycols) - 1]) AS k)
                                       || format('q.%I >> %s', v_cc, v_shift), ', '), v_queue)
           INTO v_chunks;
        PERFORM pg_advisory_xact_lock(pg_catalog.hashtextextended('tgsis chunk ' || v_table || ' ' || k, v_vid))
           FROM (SELECT k FROM unnest(v_chunks) AS k ORDER BY k) AS s;
        -- each touched chunk's visible version decoded once (its arrays unnested side by side, as the face reads
        -- them), joined with the statement's rows by key: a slot read per row detoasted the chunk's arrays once
        -- per row (1.6 s for 10,000 rows of 10 chunks)
        -- state of an UPDATE's or DELETE's row: absent (deleted meanwhile: 40001), same, changed (40001),
        -- mine (changed by this transaction since the statement read it, or gone from a chunk version it wrote:
        -- 27000); an inserted row's key present: 23505
        EXECUTE format('WITH ch AS (SELECT c.*, c.xmin = pg_catalog.xid(pg_catalog.pg_current_xact_id()) AS tgsis_mine '
                       '              FROM %1$s c WHERE %2$s AND EXISTS (SELECT FROM %3$s q WHERE %4$s)), '
                       '     d AS (SELECT %5$s, c.tgsis_mine FROM ch c%14$s CROSS JOIN LATERAL unnest(%6$s) WITH ORDINALITY AS u(%7$s, o) '
                       '            WHERE %8$s), '
                       '     s AS (SELECT %9$s AS keytext, q.tgsis_old IS NULL AS inserted, '
                       '                  CASE WHEN d.%10$I IS NULL THEN CASE WHEN c.tgsis_mine THEN ''mine'' ELSE ''absent'' END '
                       '                       WHEN ROW(%11$s)::%12$s OPERATOR(pg_catalog.*=) q.tgsis_old THEN ''same'' '
                       '                       WHEN d.tgsis_mine THEN ''mine'' ELSE ''changed'' END AS state, '
                       '                  d.%10$I IS NOT NULL AS present '
                       '             FROM %3$s q LEFT JOIN d ON %13$s LEFT JOIN ch c ON %4$s) '
                       'SELECT (array_agg(s.keytext) FILTER (WHERE NOT s.inserted AND s.state = ''absent''))[1], '
                       '       (array_agg(s.keytext) FILTER (WHERE NOT s.inserted AND s.state IN (''changed'', ''mine'')))[1], '
                       '       coalesce(bool_or(NOT s.inserted AND s.state = ''mine''), false), '
                       '       (array_agg(s.keytext) FILTER (WHERE s.inserted AND s.present))[1] '
                       '  FROM s',
                       v_chunk, v_vis, v_queue, format(v_match, 'q'),
                       v_dec.select_list, v_dec.arrays, v_dec.aliases, v_dec.present,
                       format(v_keytext, 'q'), v_keycols[1],
                       (SELECT string_agg(format('d.%I', a.attname), ', ' ORDER BY a.attnum) FROM pg_attribute a
                         WHERE a.attrelid = TG_RELID AND a.attnum > 0 AND NOT a.attisdropped),
                       v_face,
                       array_to_string(ARRAY(SELECT format('d.%1$I = q.%1$I', k) FROM unnest(v_keycols) AS k), ' AND '),
                       v_dec.joins)
           INTO v_gone, v_changed, v_mine, v_dupkey USING v_set;
        IF v_gone IS NOT NULL THEN
            RAISE EXCEPTION 'could not serialize access due to concurrent delete of row (%)=(%) of %.% in version %',
                    array_to_string(v_keycols, ', '), v_gone, v_sch, v_tname, quote_literal(tgsis.get_working_version())
                USING ERRCODE = 'serialization_failure',
                      DETAIL = 'A transaction that committed after this statement read the row deleted it.',
                      HINT = 'Retry the transaction.', TABLE = v_tname, SCHEMA = v_sch;
        END IF;
        IF v_mine THEN
            RAISE EXCEPTION 'a row (%)=(%) of %.% to be updated was already changed by an operation the current statement triggered',
                    array_to_string(v_keycols, ', '), v_changed, v_sch, v_tname
                USING ERRCODE = 'triggered_data_change_violation',
                      DETAIL = 'A function or trigger the statement ran changed the row after the statement read it.',
                      HINT = 'Change each row of a versioned view once: not both in a statement and in a function or trigger it runs.',
                      TABLE = v_tname, SCHEMA = v_sch;
        END IF;
        IF v_changed IS NOT NULL THEN
            RAISE EXCEPTION 'could not serialize access due to concurrent update of row (%)=(%) of %.% in version %',
                    array_to_string(v_keycols, ', '), v_changed, v_sch, v_tname, quote_literal(tgsis.get_working_version())
                USING ERRCODE = 'serialization_failure',
                      DETAIL = 'A transaction that committed after this statement read the row changed it; '
                               'writing values computed from the old row would undo that change.',
                      HINT = 'Retry the transaction.', TABLE = v_tname, SCHEMA = v_sch;
        END IF;
        -- an inserted row (an INSERT's, an UPDATE's new key) whose key is visible: what a plain table's key says
        IF v_dupkey IS NOT NULL THEN
            v_changed := v_dupkey;
            -- the trigger cannot tell whether the statement said ON CONFLICT (PostgreSQL does not pass the
            -- clause to it): named when the client's query has it, as today's views do, never skipped
            IF pg_catalog.current_query() ~* '\mon\s+conflict\M' THEN
                RAISE EXCEPTION 'INSERT ... ON CONFLICT is not supported on the versioned view %', v_face
                    USING ERRCODE = 'TG306',
                          DETAIL = format('Key (%s)=(%s) is there in version %s; the view cannot skip or update it as ON CONFLICT would, '
                                          'so the statement is refused and nothing is written.', array_to_string(v_keycols, ', '),
                                          v_changed, quote_literal(tgsis.get_working_version())),
                          HINT = 'insert only the keys that are not there yet, and change the others with an update',
                          TABLE = v_tname, SCHEMA = v_sch;
            END IF;
            RAISE EXCEPTION 'duplicate key value violates unique constraint "%"', v_tname || '_pkey'
                USING ERRCODE = 'unique_violation',
                      DETAIL = format('Key (%s)=(%s) already exists in version %s.', array_to_string(v_keycols, ', '), v_changed,
                                      quote_literal(tgsis.get_working_version())),
                      CONSTRAINT = v_tname || '_pkey', TABLE = v_tname, SCHEMA = v_sch;
        END IF;
        PERFORM tgsis.write_chunk_rows(v_table, v_queue::regclass);
        EXECUTE format('DELETE FROM %s', v_queue);
        IF v_split THEN
            -- the second group: the features of classes without versioning, checked and written the same way
            v_split := false;
            EXECUTE format('WITH moved AS (DELETE FROM %s RETURNING *) INSERT INTO %s SELECT * FROM moved', v_now, v_queue);
            CONTINUE groups;
        END IF;
        RETURN NULL;
    END IF;
    EXIT groups;
    END LOOP groups;
    RETURN NULL;
END
$$;

REVOKE ALL ON FUNCTION tgsis.chunk_face_write() FROM PUBLIC;

COMMENT ON FUNCTION tgsis.chunk_face_write() IS
    'AFTER statement trigger of the face of a chunk table (tgsis.create_chunk_face; TG_ARGV[0] the row table): the rows the face''s row function (<table>_face_row) kept for the statement (INSERT, UPDATE, DELETE), checked and written at once: rights, revision, object locks and notes as today''s versioned views'' triggers, the chunks'' locks in key order, each slot compared with the row read (40001, 27000), 23505 for a visible or twice-inserted key, one rewrite per touched chunk through tgsis.write_chunk_rows';
