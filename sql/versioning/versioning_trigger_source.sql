-- tgsis.versioning_trigger_source(schema, table, key columns, columns, pkey name, object class, object key column): the
-- CREATE FUNCTION statement of the INSTEAD OF trigger that routes writes on
-- the view <table> into <table>_ver. Generated per table with static SQL so
-- that PL/pgSQL caches the plans (dynamic SQL would be planned per row).
--
-- Concurrency. The view's row reached the trigger from the statement's
-- snapshot; the write is made on the row version that is current when it is
-- locked, as PostgreSQL's own re-check does for a plain table, or refused:
--   * update, delete: the visible row version of the key is locked (FOR
--     UPDATE waits for a concurrent writer and re-checks visibility after
--     it). If it is gone because that writer closed it (the first change of
--     a row inherited from an older revision writes a new row), the current
--     one is looked up again with a new snapshot. Its values must still be
--     the ones the statement read (binary equality, *=): otherwise the
--     statement computed its new values from a stale row, and the write
--     fails with 40001 (serialization_failure) naming table, key and version,
--     so that the client retries. A row deleted meanwhile is skipped, as on
--     a plain table.
--   * insert: a visible row of the key is share-locked, which waits for a
--     transaction closing it; the new row goes in with ON CONFLICT DO NOTHING
--     on the storage key, which waits for a concurrent insert of the same key
--     and revision. Either way a duplicate is the table's own 23505, never
--     one of the storage key.
--   * the object write lock (tgsis.object_lock_key) is held shared, so that
--     bulk writers of the object (check-in, save by difference, set-based
--     deletes, which take it exclusively) never decide from a state a view
--     write is changing.
-- Rights: tgsis.write_revision checks the calling role's write right on the
-- session's version for every row written here (the version is a setting
-- that a function called by the statement could change between rows) and
-- share-locks it.
--
-- Set-based updates. An UPDATE that keeps a row's key (rewriting an object's
-- values, the common bulk edit) is not written row by row: the statement's
-- first row goes the row path (a one-row UPDATE costs what it did: the
-- flush's statements cost more for one row), and for the others the row
-- trigger only queues the row's old and new values in <table>_ver_queue, and the
-- same function, fired AFTER the statement, writes all of them with a few
-- set-based statements (a versioned write per row costs some ten statements:
-- 26-40x the plain table's update, against 6-7x this way; docs/performance.md).
-- The flush does what the row path does, for all the queued rows at once:
-- the write right on the session's version (tgsis.write_revision), features
-- of no version, object locks, the notes of changed objects, the objects'
-- write locks shared, then the visible row versions locked FOR UPDATE and
-- compared with the values the statement read (40001 when one changed), then
-- closed and written anew, or changed in place. A queued row deleted by a
-- transaction that committed after the statement read it cannot be left out
-- of the statement's row count any more, as the row path does: it fails with
-- 40001 too (the retry finds no row). The queue is the table owner's alone
-- (a queue that the writing role could fill would let a role allowed to
-- change one column write any).
--
-- Which rows a flush writes. PostgreSQL fires the statement trigger once
-- per query and table, after the last of the query's UPDATEs of the view
-- (a writable CTE may hold several), and once at the end of each query run
-- inside another (by a function of its SET list, a trigger, a DO block).
-- So each view has its own generation, the setting tgsis.queue_<view oid>:
-- rows are queued under it with the transaction, and a flush counts it up
-- first, then writes every row of its transaction and generation (the
-- queue's index finds them, skipping what earlier flushes deleted): its
-- query's rows, and those an UPDATE of the view running around that query
-- queued so far (they are written a little early; that UPDATE goes on
-- under the next generation, its next row by the row path). No queued row
-- can outlive its statement: the statement's own flush comes after its
-- last row. The queue rows and the settings roll back together (a
-- savepoint, an error caught in PL/pgSQL). The first row of a generation
-- (the row path) records its key (tgsis.queue_first_<view oid>), the
-- session's version, revision and role (tgsis.queue_session_<view oid>)
-- and the version and working revision it was written in
-- (tgsis.queue_revision_<view oid>): a row queued under other settings, or
-- a flush under another revision, is refused (TG306: a function of the
-- statement moved the session to another version or saved a revision; the
-- rows would be read in one version and written in another). Two rows of
-- one key in a generation are 21000 (also when one came from an UPDATE run
-- inside the other). A row the statement read that this transaction changed
-- since (a function or trigger the statement ran), found by the row path or
-- the flush, is 27000 as on a plain table, not 40001 (a retry would meet it
-- again); a change made inside a subtransaction of that function (an
-- EXCEPTION block) has another xid and remains 40001. A role that changes tgsis.queue_<view oid> itself in
-- the middle of its own UPDATE leaves part of its rows unwritten in the
-- queue; they carry its transaction, which no other transaction's flush
-- reads.
--
-- INSERT ... ON CONFLICT: PostgreSQL runs the INSTEAD OF trigger without
-- telling it the clause (and a view has no index to infer a target from,
-- so a clause with a target is refused before the trigger runs). A plain
-- INSERT of a key that is there is the table's 23505; when the client's
-- query text has ON CONFLICT, TG306 names the clause instead. Either way
-- the statement fails and nothing is written; no row is ever skipped.
--
-- Object locks: a transaction holds one shared lock per object it writes
-- through the view, up to tgsis.object_lock_limit() objects in a version
-- (counted in tgsis.object_locks_<view oid> by the row path and the flush;
-- the same object as the row before counts once), and beyond that the
-- class's lock in the version exclusively (tgsis.object_class_lock_key,
-- which every bulk writer holds shared): the shared lock table cannot hold
-- a lock per row of a large statement (53200).
CREATE FUNCTION tgsis.versioning_trigger_source(
    p_schema    text,
    p_table     text,
    p_keys      text[],
    p_columns   text[],
    p_pkey      text,
    p_class     text,
    p_keyfield  text)
RETURNS text
LANGUAGE plpgsql
STABLE
AS $gen$
DECLARE
    v_ver      text := format('%I.%I', p_schema, p_table || '_ver');
    v_cols     text;
    v_new      text;
    v_assign   text;
    v_old_key  text;
    v_new_key  text;
    v_key_list text;
    v_visible  CONSTANT text := tgsis.visible_versions('v', 'v_set');
    v_current  text;
    v_same     text;
    v_dup      text;
    v_stale    text;
    v_noted_sql text;
    v_probe    text;
    v_declare  text := '';
    v_queue    text := format('%I.%I', p_schema, p_table || '_ver_queue');
    v_pos      integer[];    -- the position in p_columns of each key column
    v_keypos   integer;      -- ... and of the object key column
    v_enqueue  text := '';
    v_flush    text := '';
    v_qcols    text;         -- the queue's columns: depth, n<i> the new values, o<i> the old ones
    v_qvals    text;
    v_qjoin    text;
    v_qkey     text;
    v_qold     text;
    v_wrow     text;
    v_mark     text := '';   -- the row path's record of the first row of a generation
    -- the session's settings a write depends on (version, revision, role): the rows of one generation
    -- are read and written with the same
    v_session  CONSTANT text := $s$pg_catalog.format('%s/%s/%s', pg_catalog.quote_nullable(coalesce(nullif(pg_catalog.current_setting('tgsis.version', true), ''), 'DEFAULT')), pg_catalog.quote_nullable(nullif(pg_catalog.btrim(pg_catalog.current_setting('tgsis.revision', true)), '')), pg_catalog.current_setting('role'))$s$;
    v_moved_rows  text;
    v_moved_flush text;
    v_dup_insert  text;
    v_self        text;
    v_keytype     oid;       -- the object key column's type: keys as text are its canonical text (tgsis.object_key_sql)
    v_classes     boolean;   -- a model table (rows per geoid of every class): per-class rights are checked
    v_collpos     integer;   -- ... whose rows name the collection owning them (tgsis.geometry.collection): its position
BEGIN
    -- the shared model tables hold the rows of every feature class: the trigger, which writes them as
    -- the table's owner, checks the calling role's rights on the class of each object it writes
    -- (tgsis.check_class_write; docs/security.md, "Per-class rights at the model tables")
    v_classes := p_schema = 'tgsis' AND p_class = 'feature'
                 AND EXISTS (SELECT FROM tgsis.model_tables t WHERE t.tablename = p_table AND t.geoidcolumn = p_keyfield);
    -- a row that names the collection owning it is that collection's class's: the collection is checked too
    v_collpos := CASE WHEN v_classes THEN array_position(p_columns, 'collection') END;
    PERFORM tgsis.check_key_type(v_ver::regclass, p_keyfield);
    v_keytype := (SELECT a.atttypid FROM pg_catalog.pg_attribute a
                   WHERE a.attrelid = v_ver::regclass AND a.attname = p_keyfield AND NOT a.attisdropped);
    v_moved_rows := format($m$RAISE EXCEPTION 'the session''s version changed between the rows of an UPDATE of the versioned view %%', %L
                    USING ERRCODE = 'TG306',
                          DETAIL = 'Rows of the statement were written in one version (or revision, or role) and the next would be written in another; a function the statement calls changed tgsis.version, tgsis.revision or the role.',
                          HINT = 'Change the version (goto_version, SET tgsis.version) between statements, not from inside one.';$m$,
                           format('%I.%I', p_schema, p_table));
    v_moved_flush := format($m$RAISE EXCEPTION 'the session''s version changed during an UPDATE of the versioned view %%', %L
                    USING ERRCODE = 'TG306',
                          DETAIL = 'Its rows were read in one version (or revision, or role) and would be written in another; a function the statement calls changed tgsis.version, tgsis.revision or the role, or saved a revision.',
                          HINT = 'Change the version (goto_version, SET tgsis.version) between statements, not from inside one.';$m$,
                           format('%I.%I', p_schema, p_table));
    -- the probe of every row, one query: the object locks (tgsis.object_locks) and
    -- whether the object is noted as changed in the working revision
    -- (tgsis.revision_objects: what merges and conflict checks read); the check
    -- names lock holders, the note is written once per object and revision
    -- (never for revision 0: tgsis.revision_objects says why). One plain index
    -- probe for the key the row had; a new key (rare) is noted without one.
    v_noted_sql := format($noted$EXISTS (SELECT FROM tgsis.revision_objects o
                    WHERE o.revision = v_w AND o.schemaname = %L AND o.tablename = %L AND o.objectkey = v_keys[1])$noted$,
                          p_schema, p_table);
    v_probe := format($probe$-- object locks, and the note of the change: index probes in one query
    SELECT EXISTS (SELECT FROM tgsis.object_locks l WHERE l.objectclass = %1$L AND l.objectkey = ANY (v_keys)),
           %2$s
      INTO v_locked, v_noted;
    IF v_locked THEN
        PERFORM tgsis.check_objects_unlocked(%1$L, v_keys);
    END IF;
    IF v_w <> 0 AND NOT (v_noted AND (cardinality(v_keys) = 1 OR v_keys[2] = v_keys[1])) THEN
        PERFORM tgsis.record_changed_objects(%3$L, %4$L, v_keys);
    END IF;$probe$, p_class, v_noted_sql, p_schema, p_table);
    -- features of classes without versioning (tgsis.unversioned_features) are
    -- rows of no version: written with revision 0, which every revision set
    -- holds, so that the code below changes them in place and deletes them for
    -- good (and notes nothing); on the tables of object class 'feature' (keyed
    -- by geoid) only, in the same query
    IF p_class = 'feature' THEN
        v_probe := format($probe$-- object locks, features of no version and the note of the change: index probes in one query
    SELECT EXISTS (SELECT FROM tgsis.object_locks l WHERE l.objectclass = %1$L AND l.objectkey = ANY (v_keys)),
           EXISTS (SELECT FROM tgsis.unversioned_features u WHERE u.geoid = ANY (v_keys::bigint[])),
           %2$s
      INTO v_locked, v_none, v_noted;
    IF v_none THEN
        v_w := tgsis.unversioned_revision(v_keys::bigint[]);  -- 0, or TG305 outside DEFAULT's working revision
    END IF;
    IF v_locked THEN
        PERFORM tgsis.check_objects_unlocked(%1$L, v_keys);  -- names the holders
    END IF;
    IF NOT v_none AND v_w <> 0 AND NOT (v_noted AND (cardinality(v_keys) = 1 OR v_keys[2] = v_keys[1])) THEN
        PERFORM tgsis.record_changed_objects(%3$L, %4$L, v_keys);
    END IF;$probe$, p_class, v_noted_sql, p_schema, p_table);
        v_declare := E'\n    v_none   boolean;';
    END IF;
    IF v_classes THEN
        v_probe := format($check$-- the class's rights (a model table every class shares)
    IF TG_OP = 'DELETE' THEN
        PERFORM tgsis.check_class_write(v_keys::bigint[], 'UPDATE, DELETE');
    ELSE
        PERFORM tgsis.check_class_write(v_keys::bigint[]%s, 'UPDATE');
    END IF;
    $check$, CASE WHEN v_collpos IS NOT NULL THEN format(' || NEW.%I::bigint', p_columns[v_collpos]) ELSE '' END) || v_probe;
    END IF;
    SELECT string_agg(format('%I', c), ', ' ORDER BY o),
           string_agg(format('NEW.%I', c), ', ' ORDER BY o),
           string_agg(format('%I = NEW.%I', c, c), ', ' ORDER BY o),
           format('pg_catalog.record_image_eq(ROW(%s), ROW(%s))', string_agg(format('v_cur.%I', c), ', ' ORDER BY o),
                  string_agg(format('OLD.%I', c), ', ' ORDER BY o))
      INTO v_cols, v_new, v_assign, v_same
      FROM unnest(p_columns) WITH ORDINALITY AS u(c, o);
    SELECT string_agg(format('v.%I = OLD.%I', k, k), ' AND ' ORDER BY o),
           string_agg(format('v.%I = NEW.%I', k, k), ' AND ' ORDER BY o),
           string_agg(format('%I', k), ', ' ORDER BY o)
      INTO v_old_key, v_new_key, v_key_list
      FROM unnest(p_keys) WITH ORDINALITY AS u(k, o);
    -- the row version of the old key that is current now, locked: its place and revision, and its values
    -- (its place is (tableoid, ctid): a ctid alone names a row only within one table, and partitioned
    -- storage is many tables)
    v_current := format('SELECT v.tableoid AS tgsis_table_, v.ctid AS tgsis_ctid_, v.revision AS tgsis_revision_, v.xmin AS tgsis_xmin_, %s INTO v_cur FROM %s v WHERE %s AND %s FOR UPDATE',
                        (SELECT string_agg(format('v.%I', c), ', ' ORDER BY o) FROM unnest(p_columns) WITH ORDINALITY AS u(c, o)),
                        v_ver, v_old_key, v_visible);
    -- the error a plain table would raise, so applications that catch 23505 keep working
    v_dup := format($dup$
            RAISE EXCEPTION 'duplicate key value violates unique constraint %%', %L
                USING ERRCODE = 'unique_violation',
                      DETAIL = format(%L, concat_ws(', ', %s), quote_literal(tgsis.get_working_version())),
                      CONSTRAINT = %L, TABLE = %L, SCHEMA = %L;$dup$,
        '"' || p_pkey || '"',
        'Key (' || replace(v_key_list, '%', '%%') || ')=(%s) already exists in version %s.',
        (SELECT string_agg(format('NEW.%I::text', k), ', ' ORDER BY o) FROM unnest(p_keys) WITH ORDINALITY AS u(k, o)),
        p_pkey, p_table, p_schema);
    -- an INSERT of a key that is there: the trigger cannot tell whether the statement said ON CONFLICT DO
    -- NOTHING (PostgreSQL ignores the clause on a view with INSTEAD OF triggers, and a view has no unique
    -- index to infer a target from), so that it never skips a row a plain INSERT would refuse: refused by
    -- name when the client's query text has the clause, else the table's duplicate as before
    v_dup_insert := format($dup$
            IF pg_catalog.current_query() ~* '\mon\s+conflict\M' THEN
                RAISE EXCEPTION 'INSERT ... ON CONFLICT is not supported on the versioned view %%', %L
                    USING ERRCODE = 'TG306',
                          DETAIL = format(%L, concat_ws(', ', %s), quote_literal(tgsis.get_working_version())),
                          HINT = %L,
                          TABLE = %L, SCHEMA = %L;
            END IF;$dup$,
        format('%I.%I', p_schema, p_table),
        'Key (' || replace(v_key_list, '%', '%%') || ')=(%s) is there in version %s; the view cannot skip or update it as ON CONFLICT would, so the statement is refused and nothing is written.',
        (SELECT string_agg(format('NEW.%I::text', k), ', ' ORDER BY o) FROM unnest(p_keys) WITH ORDINALITY AS u(k, o)),
        format('Insert the rows whose key is not there (INSERT INTO %1$s SELECT ... WHERE NOT EXISTS (SELECT FROM %1$s WHERE (%2$s) = (...))) and UPDATE the others.',
               format('%I.%I', p_schema, p_table), v_key_list),
        p_table, p_schema) || v_dup;
    -- a row the statement read changed since by this transaction: by a function or trigger the statement
    -- ran (or by another UPDATE of the view in the same query): what PostgreSQL raises for a plain table
    -- (its re-check finds the row changed by a later command of the transaction), not 40001, which a
    -- retry would only meet again; %s: the expression of the key's text
    v_self := format($self$RAISE EXCEPTION 'a row %%%%=(%%%%) of %%%%.%%%% to be updated was already changed by an operation the current statement triggered', %L, %%s, %L, %L
                USING ERRCODE = 'triggered_data_change_violation',
                      DETAIL = 'A function or trigger the statement ran changed the row after the statement read it.',
                      HINT = 'Change each row of a versioned view once: not both in a statement and in a function or trigger it runs.',
                      TABLE = %L, SCHEMA = %L;$self$,
        '(' || replace(v_key_list, '%', '%%') || ')', replace(p_schema, '%', '%%'), replace(p_table, '%', '%%'),
        replace(p_table, '%', '%%'), replace(p_schema, '%', '%%'));
    -- what PostgreSQL raises when a repeatable-read transaction meets a concurrent update: clients retry it
    v_stale := format($stale$
            RAISE EXCEPTION 'could not serialize access due to concurrent update of row %%=(%%) of %%.%% in version %%',
                    %L, concat_ws(', ', %s), %L, %L, quote_literal(tgsis.get_working_version())
                USING ERRCODE = 'serialization_failure',
                      DETAIL = 'A transaction that committed after this statement read the row changed or replaced it; '
                               'writing values computed from the old row would undo that change.',
                      HINT = 'Retry the transaction.',
                      TABLE = %L, SCHEMA = %L;$stale$,
        '(' || v_key_list || ')',
        (SELECT string_agg(format('OLD.%I::text', k), ', ' ORDER BY o) FROM unnest(p_keys) WITH ORDINALITY AS u(k, o)),
        p_schema, p_table, p_table, p_schema);

    -- the set-based path of key-keeping updates, when every key column is a writable one
    SELECT array_agg(array_position(p_columns, k) ORDER BY o) INTO v_pos FROM unnest(p_keys) WITH ORDINALITY AS u(k, o);
    v_keypos := array_position(p_columns, p_keyfield);
    IF array_position(v_pos, NULL) IS NULL AND v_keypos IS NOT NULL THEN
        SELECT 'tgsis_xact, tgsis_generation, '
                               || string_agg(format('n%s', o), ', ' ORDER BY o) || ', '
                               || string_agg(format('o%s', o), ', ' ORDER BY o),
               'pg_catalog.pg_current_xact_id(), v_gen, '
                                                 || string_agg(format('NEW.%I', c), ', ' ORDER BY o) || ', '
                                                 || string_agg(format('OLD.%I', c), ', ' ORDER BY o),
               format('pg_catalog.record_image_eq(ROW(%s), ROW(%s))', string_agg(format('v.%I', c), ', ' ORDER BY o),
                      string_agg(format('q.o%s', o), ', ' ORDER BY o))
          INTO v_qcols, v_qvals, v_qold
          FROM unnest(p_columns) WITH ORDINALITY AS u(c, o);
        SELECT string_agg(format('v.%I = q.n%s', k, v_pos[o]), ' AND ' ORDER BY o),
               format('concat_ws(%L, %s)', ', ', string_agg(format('q.n%s::text', v_pos[o]), ', ' ORDER BY o))
          INTO v_qjoin, v_qkey
          FROM unnest(p_keys) WITH ORDINALITY AS u(k, o);
        -- the revision a queued row is written with: 0 for features of no version (p_class 'feature' only)
        v_wrow := CASE WHEN p_class = 'feature'
                       THEN format('CASE WHEN q.n%s::text = ANY (v_unversioned) THEN 0 ELSE v_w END', v_keypos)
                       ELSE 'v_w' END;
        v_enqueue := format($enq$
    IF TG_OP = 'UPDATE' AND pg_catalog.record_image_eq(ROW(%1$s), ROW(%2$s)) THEN
        -- the key stays: the first row since the view's last flush goes the row path below (a one-row
        -- UPDATE costs what it did), the others are queued under the view's generation and written when
        -- the statement ends (the flush above); tgsis.queue_first_<view> says "<generation>:<key>" of
        -- that first row, tgsis.queue_session_<view> the session's version settings it was written with
        v_gen := coalesce(nullif(pg_catalog.current_setting('tgsis.queue_' || TG_RELID, true), ''), '0')::bigint;
        IF pg_catalog.split_part(pg_catalog.current_setting('tgsis.queue_first_' || TG_RELID, true),
                                 ':', 1) = v_gen::text THEN
            IF pg_catalog.current_setting('tgsis.queue_session_' || TG_RELID, true) IS DISTINCT FROM %7$s THEN
                %8$s
            END IF;
            INSERT INTO %3$s (%4$s) VALUES (%5$s);
            RETURN NEW;
        END IF;
        v_first := v_gen || ':' || %6$s;
    END IF;$enq$,
            (SELECT string_agg(format('NEW.%I', k), ', ' ORDER BY o) FROM unnest(p_keys) WITH ORDINALITY AS u(k, o)),
            (SELECT string_agg(format('OLD.%I', k), ', ' ORDER BY o) FROM unnest(p_keys) WITH ORDINALITY AS u(k, o)),
            v_queue, v_qcols, v_qvals,
            format('concat_ws(%L, %s)', ', ', (SELECT string_agg(format('NEW.%I::text', k), ', ' ORDER BY o)
                                                 FROM unnest(p_keys) WITH ORDINALITY AS u(k, o))),
            v_session, v_moved_rows);
        v_flush := format($flush$
    IF TG_LEVEL = 'STATEMENT' THEN
        -- the end of an UPDATE of the view (of the last of its UPDATEs in one query: PostgreSQL fires one
        -- statement trigger per query and table): write every row queued for the view since its last
        -- flush in this transaction (%1$s, the view's generation), all at once. Those are this query's
        -- rows, and those of an UPDATE of the view still running around it (a function or trigger ran
        -- this query from inside it): written now, they are what that UPDATE would have written so far.
        v_xact := pg_catalog.pg_current_xact_id_if_assigned();
        v_gen := coalesce(nullif(pg_catalog.current_setting('tgsis.queue_' || TG_RELID, true), ''), '0')::bigint;
        -- first: an UPDATE of the view that the writes below run (a trigger of the storage) queues
        -- under the next generation, its first row the row path
        PERFORM pg_catalog.set_config('tgsis.queue_' || TG_RELID, (v_gen + 1)::text, true);
        IF v_xact IS NULL THEN
            RETURN NULL;  -- nothing written, nothing queued
        END IF;
        SELECT count(*), count(DISTINCT ROW(%2$s)), array_agg(DISTINCT %23$s ORDER BY %23$s)
          INTO v_count, v_distinct, v_keys
          FROM %1$s q WHERE q.tgsis_xact = v_xact AND q.tgsis_generation = v_gen;
        IF v_count = 0 THEN
            RETURN NULL;
        END IF;
        -- the first row, written by the row path, queued again: the same row twice
        v_first := pg_catalog.current_setting('tgsis.queue_first_' || TG_RELID, true);
        IF pg_catalog.split_part(v_first, ':', 1) = v_gen::text AND EXISTS (
                SELECT FROM %1$s q
                 WHERE q.tgsis_xact = v_xact AND q.tgsis_generation = v_gen
                   AND %9$s = pg_catalog.substr(v_first, pg_catalog.strpos(v_first, ':') + 1)) THEN
            v_distinct := v_distinct - 1;
        END IF;
        IF v_distinct <> v_count THEN
            RAISE EXCEPTION 'one statement changed a row of %%.%% twice', %4$L, %5$L
                USING ERRCODE = 'cardinality_violation',
                      DETAIL = 'Counted together: the UPDATEs of the view in one query (writable CTEs), and those run by '
                               'functions or triggers while an UPDATE of the view was running.',
                      HINT = 'change each row of a versioned view once in a statement';
        END IF;
        -- the session's version, revision and role must be those the rows were read in
        IF pg_catalog.current_setting('tgsis.queue_session_' || TG_RELID, true) IS DISTINCT FROM %20$s THEN
            %21$s
        END IF;
        SELECT w.versionid, w.revision, w.revisions INTO v_vid, v_w, v_set FROM tgsis.write_revision() AS w;
        IF pg_catalog.current_setting('tgsis.queue_revision_' || TG_RELID, true) IS DISTINCT FROM v_vid || ':' || v_w THEN
            %21$s
        END IF;
        %6$s
        IF EXISTS (SELECT FROM tgsis.object_locks l WHERE l.objectclass = %7$L AND l.objectkey = ANY (v_keys)) THEN
            PERFORM tgsis.check_objects_unlocked(%7$L, v_keys);  -- names the holders
        END IF;
        IF v_w <> 0 THEN
            PERFORM tgsis.record_changed_objects(%4$L, %5$L, %8$s);
        END IF;
        -- no bulk writer of the objects in flight: their write locks shared (bulk writers take them
        -- exclusively), in key order; beyond tgsis.object_lock_limit() objects locked through the view
        -- in the transaction and version (the shared lock table holds max_locks_per_transaction locks
        -- per connection), the class's lock in the version, exclusively: every bulk writer of the class
        -- holds it shared (tgsis.object_write_lock). Counted as by the row path below.
        v_held := coalesce(pg_catalog.current_setting('tgsis.object_locks_' || TG_RELID, true), '');
        IF v_held = v_vid || ':*' THEN
            PERFORM pg_catalog.pg_advisory_xact_lock(tgsis.object_class_lock_key(%7$L, v_vid));  -- held: taken again
        ELSE
            v_n := CASE WHEN pg_catalog.split_part(v_held, ':', 1) = v_vid::text
                        THEN pg_catalog.split_part(v_held, ':', 2)::integer ELSE 0 END;
            IF v_n + cardinality(v_keys) > tgsis.object_lock_limit() THEN
                PERFORM pg_catalog.pg_advisory_xact_lock(tgsis.object_class_lock_key(%7$L, v_vid));
                PERFORM pg_catalog.set_config('tgsis.object_locks_' || TG_RELID, v_vid || ':*', true);
            ELSE
                PERFORM pg_catalog.pg_advisory_xact_lock_shared(tgsis.object_lock_key(%7$L, k, v_vid))
                   FROM pg_catalog.unnest(v_keys) AS k;
                PERFORM pg_catalog.set_config('tgsis.object_locks_' || TG_RELID,
                                              v_vid || ':' || (v_n + cardinality(v_keys)) || ':', true);
            END IF;
        END IF;
        -- the visible row versions, locked, and compared with what the statement read; a row closed by a
        -- transaction that committed meanwhile drops out of the join (the re-check after the wait): once
        -- more with a new snapshot, which sees the row version that replaced it
        FOR v_pass IN 1 .. 2 LOOP
            SELECT count(*), (array_agg(x.k ORDER BY NOT x.mine) FILTER (WHERE NOT x.same))[1],
                   coalesce(bool_or(x.mine AND NOT x.same), false)
              INTO v_found, v_key, v_mine
              FROM (SELECT %9$s AS k, %10$s AS same, v.xmin = pg_catalog.xid(v_xact) AS mine
                      FROM %1$s q JOIN %11$s v ON %12$s AND %13$s
                     WHERE q.tgsis_xact = v_xact AND q.tgsis_generation = v_gen
                       FOR UPDATE OF v) AS x;
            EXIT WHEN v_found = v_count;
        END LOOP;
        IF v_found <> v_count THEN
            SELECT %9$s INTO v_key FROM %1$s q
             WHERE q.tgsis_xact = v_xact AND q.tgsis_generation = v_gen
               AND NOT EXISTS (SELECT FROM %11$s v WHERE %12$s AND %13$s)
             LIMIT 1;
            RAISE EXCEPTION 'could not serialize access due to concurrent delete of row %%=(%%) of %%.%% in version %%',
                    %14$L, v_key, %4$L, %5$L, quote_literal(tgsis.get_working_version())
                USING ERRCODE = 'serialization_failure',
                      DETAIL = 'A transaction that committed after this statement read the row deleted it or changed its key.',
                      HINT = 'Retry the transaction.',
                      TABLE = %5$L, SCHEMA = %4$L;
        END IF;
        IF v_mine THEN
            %22$s
        END IF;
        IF v_key IS NOT NULL THEN
            RAISE EXCEPTION 'could not serialize access due to concurrent update of row %%=(%%) of %%.%% in version %%',
                    %14$L, v_key, %4$L, %5$L, quote_literal(tgsis.get_working_version())
                USING ERRCODE = 'serialization_failure',
                      DETAIL = 'A transaction that committed after this statement read the row changed or replaced it; '
                               'writing values computed from the old row would undo that change.',
                      HINT = 'Retry the transaction.',
                      TABLE = %5$L, SCHEMA = %4$L;
        END IF;
        -- row versions of the working revision: changed in place (first: the rows written anew below are of it too)
        UPDATE %11$s v SET %19$s
          FROM %1$s q
         WHERE q.tgsis_xact = v_xact AND q.tgsis_generation = v_gen AND %12$s AND %13$s AND v.revision = %15$s;
        -- row versions of older revisions: closed in the working one, and written anew in it
        WITH closed AS (
            UPDATE %11$s v SET lastrevs = v.lastrevs || %15$s
              FROM %1$s q
             WHERE q.tgsis_xact = v_xact AND q.tgsis_generation = v_gen AND %12$s AND %13$s AND v.revision <> %15$s
            RETURNING %16$s, %15$s AS tgsis_revision_),
        written AS (
            INSERT INTO %11$s (%17$s, revision) SELECT %17$s, tgsis_revision_ FROM closed
                ON CONFLICT ON CONSTRAINT %18$I DO NOTHING
            RETURNING 1)
        SELECT (SELECT count(*) FROM closed), (SELECT count(*) FROM written) INTO v_closed, v_written;
        IF v_written <> v_closed THEN
            RAISE EXCEPTION 'could not serialize access due to concurrent update of rows of %%.%% in version %%',
                    %4$L, %5$L, quote_literal(tgsis.get_working_version())
                USING ERRCODE = 'serialization_failure',
                      DETAIL = 'A row version of the working revision was written for a key by a transaction that committed meanwhile.',
                      HINT = 'Retry the transaction.',
                      TABLE = %5$L, SCHEMA = %4$L;
        END IF;
        DELETE FROM %1$s q WHERE q.tgsis_xact = v_xact AND q.tgsis_generation = v_gen;
        RETURN NULL;
    END IF;$flush$,
            v_queue,                                                                           -- 1
            (SELECT string_agg(format('q.n%s', p), ', ' ORDER BY o) FROM unnest(v_pos) WITH ORDINALITY AS u(p, o)),  -- 2
            v_keypos, p_schema, p_table,                                                       -- 3, 4, 5
            CASE WHEN p_class = 'feature' THEN
                $none$-- features of no version among them: written with revision 0, only from DEFAULT's working revision
        v_unversioned := ARRAY(SELECT k FROM pg_catalog.unnest(v_keys) AS k
                                WHERE EXISTS (SELECT FROM tgsis.unversioned_features u WHERE u.geoid = k::bigint));
        IF cardinality(v_unversioned) > 0 THEN
            PERFORM tgsis.unversioned_revision(v_unversioned::bigint[]);  -- TG305 outside DEFAULT's working revision
        END IF;$none$
            ELSE '' END
            || CASE WHEN v_classes THEN format($check$
        PERFORM tgsis.check_class_write(v_keys::bigint[]%s, 'UPDATE');  -- the class's rights (a model table)$check$,
                   CASE WHEN v_collpos IS NOT NULL  -- and of the collections the rows now name
                        THEN format(' || ARRAY(SELECT DISTINCT q.n%s::bigint FROM %s q WHERE q.tgsis_xact = v_xact '
                                    'AND q.tgsis_generation = v_gen AND q.n%s IS NOT NULL)', v_collpos, v_queue, v_collpos)
                        ELSE '' END)
               ELSE '' END,                                                                    -- 6
            p_class,                                                                           -- 7
            CASE WHEN p_class = 'feature' THEN 'ARRAY(SELECT k FROM pg_catalog.unnest(v_keys) AS k WHERE NOT (k = ANY (v_unversioned)))'
                 ELSE 'v_keys' END,                                                            -- 8
            v_qkey, v_qold, v_ver, v_qjoin, v_visible,                                        -- 9 .. 13
            '(' || v_key_list || ')',                                                          -- 14
            v_wrow,                                                                            -- 15
            (SELECT string_agg(format('q.n%s AS %I', o, c), ', ' ORDER BY o) FROM unnest(p_columns) WITH ORDINALITY AS u(c, o)),  -- 16
            v_cols,                                                                            -- 17
            p_table || '_ver_pkey',                                                            -- 18
            (SELECT string_agg(format('%I = q.n%s', c, o), ', ' ORDER BY o) FROM unnest(p_columns) WITH ORDINALITY AS u(c, o)),  -- 19
            v_session, v_moved_flush,                                                          -- 20, 21
            format(v_self, 'v_key'),                                                           -- 22
            tgsis.object_key_sql(v_keytype, format('q.n%s', v_keypos)));                      -- 23
        v_declare := v_declare || E'
    v_xact     xid8;
    v_count    bigint;
    v_first    text;
    v_distinct bigint;
    v_found    bigint;'
                               || E'
    v_closed   bigint;
    v_written  bigint;
    v_mine     boolean;
    v_key      text;
    v_pass     integer;';
        v_declare := v_declare || E'\n    v_gen      bigint;';
        v_mark := format($mark$
    IF v_first IS NOT NULL THEN
        -- the first row of the view's generation: the rows queued after it are read with the same settings
        PERFORM pg_catalog.set_config('tgsis.queue_first_' || TG_RELID, v_first, true),
                pg_catalog.set_config('tgsis.queue_session_' || TG_RELID, %s, true),
                pg_catalog.set_config('tgsis.queue_revision_' || TG_RELID, v_vid || ':' || v_w, true);
    END IF;$mark$, v_session);
        IF p_class = 'feature' THEN
            v_declare := v_declare || E'\n    v_unversioned text[];';
        END IF;
    ELSE
        -- a key column that is not written (a generated one): every row goes the row path
        v_flush := E'\n    IF TG_LEVEL = ''STATEMENT'' THEN\n        RETURN NULL;\n    END IF;';
    END IF;

    RETURN format($fn$
CREATE FUNCTION %1$I.%2$I()
RETURNS trigger
LANGUAGE plpgsql
SECURITY DEFINER
SET search_path = pg_catalog, pg_temp
AS $body$
-- Written by tgsis.enable_versioning: writes on the view %1$s.%3$s go to %4$s
-- as row versions labelled with the session's working revision (see
-- tgsis.versioning_trigger_source for how concurrent writers are handled).
DECLARE
    v_vid  integer;
    v_w    integer;
    v_set  integer[];
    v_keys text[];
    v_cur  record;
    v_locked boolean;
    v_noted  boolean;
    v_held   text;
    v_n      integer;
    v_new    integer;%21$s
BEGIN%22$s%23$s
    -- the write right on the session's version (checked for every row), its working revision and set
    SELECT w.versionid, w.revision, w.revisions INTO v_vid, v_w, v_set FROM tgsis.write_revision() AS w;%24$s
    IF TG_OP = 'INSERT' THEN
        v_keys := ARRAY[%27$s];
    ELSIF TG_OP = 'DELETE' THEN
        v_keys := ARRAY[%28$s];
    ELSE
        v_keys := ARRAY[%28$s, %27$s];
    END IF;
    %20$s
    -- no bulk writer of the object in flight (they take its write lock exclusively): its lock shared; once
    -- the transaction locked tgsis.object_lock_limit() objects through the view in the version, the class's
    -- lock in the version exclusively instead (bulk writers hold it shared), which covers all the others
    -- (tgsis.object_locks_<view oid> counts: "<version id>:<objects>:<last object>", or "<version id>:*")
    v_held := coalesce(pg_catalog.current_setting('tgsis.object_locks_' || TG_RELID, true), '');
    IF v_held = v_vid || ':*' THEN
        -- held already (taken again: a lookup in this session's lock table, and the setting, which the
        -- session could change itself, is never trusted to skip a lock)
        PERFORM pg_catalog.pg_advisory_xact_lock(tgsis.object_class_lock_key(%14$L, v_vid));
    ELSE
        v_n := CASE WHEN pg_catalog.split_part(v_held, ':', 1) = v_vid::text
                    THEN pg_catalog.split_part(v_held, ':', 2)::integer ELSE 0 END;
        v_new := CASE WHEN cardinality(v_keys) = 2 AND v_keys[2] IS DISTINCT FROM v_keys[1] THEN 2
                      WHEN v_held = v_vid || ':' || v_n || ':' || v_keys[1] THEN 0  -- the last row's object
                      ELSE 1 END;
        IF v_n + v_new > tgsis.object_lock_limit() THEN
            PERFORM pg_catalog.pg_advisory_xact_lock(tgsis.object_class_lock_key(%14$L, v_vid));
            PERFORM pg_catalog.set_config('tgsis.object_locks_' || TG_RELID, v_vid || ':*', true);
        ELSE
            PERFORM pg_catalog.pg_advisory_xact_lock_shared(tgsis.object_lock_key(%14$L, v_keys[1], v_vid));
            IF v_new = 2 THEN
                PERFORM pg_catalog.pg_advisory_xact_lock_shared(tgsis.object_lock_key(%14$L, v_keys[2], v_vid));
            END IF;
            IF v_new > 0 THEN
                PERFORM pg_catalog.set_config('tgsis.object_locks_' || TG_RELID,
                                              v_vid || ':' || (v_n + v_new) || ':' || v_keys[cardinality(v_keys)], true);
            END IF;
        END IF;
    END IF;

    IF TG_OP = 'INSERT' THEN
        -- a visible row of the key: wait for a transaction closing it; if it stays, a duplicate
        PERFORM FROM %4$s v WHERE %6$s AND %9$s FOR SHARE;
        IF FOUND THEN%25$s
        END IF;
        -- waits for a concurrent insert of the same key in this revision
        INSERT INTO %4$s (%5$s, revision) VALUES (%7$s, v_w) ON CONFLICT ON CONSTRAINT %16$I DO NOTHING;
        IF NOT FOUND THEN%25$s
        END IF;
        RETURN NEW;
    END IF;

    %17$s;
    IF NOT FOUND THEN
        -- a transaction that committed since this statement read the row closed it: the row current now, if any
        %17$s;
        IF NOT FOUND THEN
            RETURN NULL;  -- deleted meanwhile: nothing to change, as on a plain table
        END IF;
    END IF;
    IF NOT (%18$s) THEN
        IF v_cur.tgsis_xmin_ = pg_catalog.xid(pg_catalog.pg_current_xact_id()) THEN
            %26$s
        END IF;%19$s
    END IF;

    IF TG_OP = 'UPDATE' THEN
        IF ROW(%11$s) IS DISTINCT FROM ROW(%12$s) THEN
            -- a new key is a delete of the old key and an insert of the new one
            PERFORM FROM %4$s v WHERE %6$s AND %9$s FOR SHARE;
            IF FOUND THEN%10$s
            END IF;
            IF v_cur.tgsis_revision_ = v_w THEN
                DELETE FROM %4$s v WHERE v.tableoid = v_cur.tgsis_table_ AND v.ctid = v_cur.tgsis_ctid_;
            ELSE
                UPDATE %4$s v SET lastrevs = v.lastrevs || v_w WHERE v.tableoid = v_cur.tgsis_table_ AND v.ctid = v_cur.tgsis_ctid_;
            END IF;
            INSERT INTO %4$s (%5$s, revision) VALUES (%7$s, v_w) ON CONFLICT ON CONSTRAINT %16$I DO NOTHING;
            IF NOT FOUND THEN%10$s
            END IF;
        ELSIF v_cur.tgsis_revision_ = v_w THEN
            UPDATE %4$s v SET %8$s WHERE v.tableoid = v_cur.tgsis_table_ AND v.ctid = v_cur.tgsis_ctid_;
        ELSE
            UPDATE %4$s v SET lastrevs = v.lastrevs || v_w WHERE v.tableoid = v_cur.tgsis_table_ AND v.ctid = v_cur.tgsis_ctid_;
            INSERT INTO %4$s (%5$s, revision) VALUES (%7$s, v_w) ON CONFLICT ON CONSTRAINT %16$I DO NOTHING;
            IF NOT FOUND THEN%19$s
            END IF;
        END IF;
        RETURN NEW;
    END IF;
    IF v_cur.tgsis_revision_ = v_w THEN
        DELETE FROM %4$s v WHERE v.tableoid = v_cur.tgsis_table_ AND v.ctid = v_cur.tgsis_ctid_;
    ELSE
        UPDATE %4$s v SET lastrevs = v.lastrevs || v_w WHERE v.tableoid = v_cur.tgsis_table_ AND v.ctid = v_cur.tgsis_ctid_;
    END IF;
    RETURN OLD;
END
$body$$fn$,
        p_schema, p_table || '_ver_write', p_table, v_ver, v_cols, v_new_key, v_new, v_assign, v_visible, v_dup,
        (SELECT string_agg(format('NEW.%I', k), ', ' ORDER BY o) FROM unnest(p_keys) WITH ORDINALITY AS u(k, o)),
        (SELECT string_agg(format('OLD.%I', k), ', ' ORDER BY o) FROM unnest(p_keys) WITH ORDINALITY AS u(k, o)),
        v_old_key, p_class, p_keyfield, p_table || '_ver_pkey', v_current, v_same, v_stale, v_probe, v_declare,
        v_flush, v_enqueue, v_mark, v_dup_insert,
        format(v_self, format('concat_ws(%L, %s)', ', ', (SELECT string_agg(format('OLD.%I::text', k), ', ' ORDER BY o)
                                                          FROM unnest(p_keys) WITH ORDINALITY AS u(k, o)))),
        tgsis.object_key_sql(v_keytype, format('NEW.%I', p_keyfield)), tgsis.object_key_sql(v_keytype, format('OLD.%I', p_keyfield)));
END
$gen$;

COMMENT ON FUNCTION tgsis.versioning_trigger_source(text, text, text[], text[], text, text, text) IS
    'source of the INSTEAD OF INSERT/UPDATE/DELETE trigger function <table>_ver_write() that enable_versioning creates: writes on the row version current when locked, or 40001 when the statement read a row a concurrent transaction changed';
