-- tgsis.chunk_face_write(): the INSTEAD OF trigger of a chunk table's face (tgsis.create_chunk_face), TG_ARGV[0] the row table.
-- Writes on the face go into tgsis.<table>_chunk through the one writer of
-- chunk contents, tgsis.write_chunk_rows, keeping the guarantees of today's
-- versioned views' triggers (tgsis.versioning_trigger_source), row for row:
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
--     retry would fail again), deleted meanwhile is
--     skipped (DELETE, UPDATE of the key) as on a plain table. Other slots
--     keep what concurrent writers committed: the writer merges into the
--     current chunk. Two face writers of different slots of one chunk wait
--     for each other (the lock is the chunk's), and two chunks locked in
--     opposite orders can deadlock (40P01) where rows would not;
--   * INSERT of a visible key is 23505 naming today's key (<table>_pkey), TG306
--     when the client's query says ON CONFLICT (as today's views); an
--     UPDATE changing the key is a delete of the old key and an insert of the
--     new (23505 when it is there); RETURNING returns the row written;
--   * an UPDATE keeping the key is queued (pg_temp.tgsis_face_queue_<view oid>,
--     the session's, owned by the storage's owner) and written when the
--     statement ends (this function, fired AFTER the UPDATE statement): all
--     queued rows at once, the chunks they touch locked in key order, compared
--     set-based, written by one call of tgsis.write_chunk_rows (a key twice in
--     one statement: 21000); a statement changing features of versioned
--     classes and of classes without versioning (which no row leaves: each
--     keeps its key) is written in two groups, the latter in revision 0, as
--     today's view writes row by row (one group's revision for both was
--     TG300). INSERT, DELETE and key changes are written per
--     row through pg_temp.tgsis_face_now_<view oid>.
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
    v_now       text := format('pg_temp.%I', 'tgsis_face_now_' || TG_RELID);
    v_queue     text := format('pg_temp.%I', 'tgsis_face_queue_' || TG_RELID);
    v_kc        text;      -- the object key column (geoid)
    v_cc        text;      -- the chunk column (the local id)
    v_keycols   text[];    -- the row key: the key columns, then the chunk column
    v_mask      bigint;
    v_shift     integer;
    v_keys      text[];    -- the object keys written, as text
    v_geoids    bigint[];
    v_vid       integer;
    v_w         integer;
    v_set       integer[];
    v_vis       text := '(c.revision = ANY ($1)) IS TRUE AND NOT (c.lastrevs && $1)';
    v_match     text;      -- the chunk version of the row %1$s: key and chunk
    v_slot      text;
    v_first     text;      -- the first ref column
    v_decoded   text;
    v_present   text;
    v_locate    text;
    v_keytext   text;
    v_state     text;      -- of the row's slot now: absent, same, changed, mine (changed by this transaction)
    v_chunks    text[];
    v_count     bigint;
    v_distinct  bigint;
    v_gone      text;
    v_changed   text;
    v_mine      boolean;
    v_dup       boolean;
    v_tab       text;
    v_split     boolean;   -- the flush's second group (features of classes without versioning) waits in v_now
    v_moved     bigint;
BEGIN
    SELECT * INTO v_reg FROM tgsis.chunk_registry(v_table) r;
    v_objclass := coalesce((SELECT t.objectclass FROM tgsis.model_tables t WHERE t.tablename = v_reg.tablename AND v_reg.classname IS NULL),
                           'feature');
    v_sch := v_reg.schemaname;
    v_tname := v_reg.tablename;
    v_chunk := tgsis.chunk_relation(v_table, '_chunk');
    v_kc := v_reg.keycolumn;
    v_cc := v_reg.chunkcolumn;
    v_mask := v_reg.chunksize - 1;
    v_shift := round(log(2, v_reg.chunksize))::integer;
    -- the row key: the chunk table's key columns before revision, the chunk column last (in place of chunk),
    -- from the catalog in one query: the queued path of an UPDATE needs nothing more
    SELECT array_agg(CASE WHEN a.attname = 'chunk' THEN v_cc ELSE a.attname::text END ORDER BY a.attnum) INTO v_keycols
      FROM pg_attribute a
     WHERE a.attrelid = v_chunk::regclass AND a.attnum > 0
       AND a.attnum < (SELECT r.attnum FROM pg_attribute r WHERE r.attrelid = v_chunk::regclass AND r.attname = 'revision');
    IF TG_LEVEL = 'ROW' AND TG_OP = 'UPDATE' THEN
        -- (the key columns are bigint and time values: their jsonb forms are equal when they are)
        v_dup := (SELECT bool_and(o.j -> k = n.j -> k)
                    FROM (SELECT to_jsonb(OLD) AS j) o, (SELECT to_jsonb(NEW) AS j) n, unnest(v_keycols) AS k);
        IF v_dup THEN
            -- the key stays: queued with the row read, checked and written when the statement ends
            IF to_regclass(v_queue) IS NULL THEN
                EXECUTE format('CREATE TEMP TABLE %s (LIKE %s, _delete boolean NOT NULL DEFAULT false, tgsis_old %s) '
                               'ON COMMIT DELETE ROWS', v_queue, v_face, v_face);
            ELSIF (SELECT c.relowner FROM pg_class c WHERE c.oid = to_regclass(v_queue)) <> (SELECT r.oid FROM pg_roles r WHERE r.rolname = current_user) THEN
                RAISE EXCEPTION 'the session''s table % was not made by the face''s trigger', v_queue
                    USING ERRCODE = 'insufficient_privilege', HINT = 'drop the temporary table and write again';
            END IF;
            EXECUTE format('INSERT INTO %s SELECT ($1).*, false, $2', v_queue) USING NEW, OLD;
            RETURN NEW;
        END IF;
    END IF;
    -- the pieces of the statements below, for a row %1$s of the face's type ($3, or the queue's q)
    v_match := array_to_string(ARRAY(SELECT format('c.%I = (%%1$s).%I', k, k) FROM unnest(v_keycols[1:cardinality(v_keycols) - 1]) AS k)
                               || format('c.chunk = (%%1$s).%I >> %s', v_cc, v_shift), ' AND ');
    v_slot := format('(((%%1$s).%I & %s) + 1)::integer', v_cc, v_mask);
    v_first := (SELECT c.name FROM tgsis.chunk_columns(v_table) c WHERE c.role = 'ref' ORDER BY c.colorder LIMIT 1);
    SELECT format('ROW(%s)::%s', string_agg(
               CASE WHEN c.role IN ('key', 'chunk') THEN format('(%%1$s).%I', c.name)
                    WHEN c.role IN ('float', 'value') THEN format('c.%I[%s]', c.name, v_slot)
                    -- a vector property's row of its 2-D array (NULL: a NULL vector; tgsis.chunk_decode_sql's form)
                    WHEN c.role = 'vector' THEN format('CASE WHEN c.%I[%s][1] IS NULL THEN NULL ELSE ARRAY[%s] END', c.name, v_slot,
                                                       (SELECT string_agg(format('c.%I[%s][%s]', c.name, v_slot, i), ', ' ORDER BY i)
                                                          FROM generate_series(1, c.size) AS i))
                    ELSE format('CASE WHEN c.vbase IS NOT NULL THEN c.vbase + %s ELSE c.%I[%s] END',
                                CASE WHEN c.name = v_first THEN format('c.%I[%s]', c.name, v_slot)
                                     ELSE format('c.%I[%s] + c.%I[%s]', v_first, v_slot, c.name, v_slot) END,
                                c.name || '_wide', v_slot) END, ', ' ORDER BY c.colorder), v_face)
      INTO v_decoded
      FROM tgsis.chunk_columns(v_table) c;
    v_present := (SELECT CASE WHEN f.role = 'value' THEN format('(%s <= cardinality(c.%I) AND NOT coalesce(%s = ANY (c.holes), false))',
                                                                v_slot, f.name, v_slot)
                              WHEN f.role = 'vector' THEN format('(%s <= array_length(c.%I, 1) AND NOT coalesce(%s = ANY (c.holes), false))',
                                                                 v_slot, f.name, v_slot)
                              WHEN f.role = 'float' THEN format('c.%I[%s] IS NOT NULL', f.name, v_slot)
                              ELSE format('(c.%I[%s] IS NOT NULL OR c.%I[%s] IS NOT NULL)', f.name, v_slot, f.name || '_wide', v_slot) END
                    FROM tgsis.chunk_columns(v_table) f WHERE f.role IN ('float', 'ref', 'value', 'vector') ORDER BY f.colorder LIMIT 1);
    v_keytext := format('concat_ws(%L, %s)', ', ',
                        (SELECT string_agg(format('(%%1$s).%I::text', k), ', ' ORDER BY o) FROM unnest(v_keycols) WITH ORDINALITY AS u(k, o)));
    -- the state of the row's slot in the visible version of its chunk, read with this statement's snapshot
    v_locate := format('SELECT CASE WHEN NOT (%2$s) THEN ''absent'' WHEN %3$s OPERATOR(pg_catalog.*=) %4$s THEN ''same'' '
                       'WHEN c.xmin = pg_catalog.xid(pg_catalog.pg_current_xact_id()) THEN ''mine'' ELSE ''changed'' END '
                       'FROM %5$s c WHERE %6$s AND %7$s',
                       NULL, format(v_present, '$2'), format(v_decoded, '$2'), '$3', v_chunk, format(v_match, '$2'), v_vis);

    -- the session's temporary tables of rows to write: the face's columns, _delete, the row read
    FOREACH v_tab IN ARRAY ARRAY[v_now, v_queue] LOOP
        IF to_regclass(v_tab) IS NULL THEN
            EXECUTE format('CREATE TEMP TABLE %s (LIKE %s, _delete boolean NOT NULL DEFAULT false, tgsis_old %s) ON COMMIT DELETE ROWS',
                           v_tab, v_face, v_face);
        ELSIF (SELECT c.relowner FROM pg_class c WHERE c.oid = to_regclass(v_tab)) <> (SELECT r.oid FROM pg_roles r WHERE r.rolname = current_user) THEN
            RAISE EXCEPTION 'the session''s table % was not made by the face''s trigger', v_tab
                USING ERRCODE = 'insufficient_privilege', HINT = 'drop the temporary table and write again';
        END IF;
    END LOOP;

    <<groups>>
    LOOP
    IF TG_LEVEL = 'STATEMENT' AND v_split IS NULL THEN
        -- features of classes without versioning are written in revision 0, the others in the working revision:
        -- when the statement changed both, those of no version wait in v_now (empty between rows) for a second pass
        v_split := false;
        IF v_objclass = 'feature'
           AND EXISTS (SELECT FROM tgsis.versioned_tables t WHERE t.schemaname = v_sch AND t.tablename = v_tname) THEN
            EXECUTE format('WITH moved AS (DELETE FROM %1$s q WHERE q.%3$I IN (SELECT u.geoid FROM tgsis.unversioned_features u) '
                           '  AND EXISTS (SELECT FROM %1$s o WHERE o.%3$I NOT IN (SELECT u.geoid FROM tgsis.unversioned_features u)) '
                           'RETURNING q.*) INSERT INTO %2$s SELECT * FROM moved', v_queue, v_now, v_kc);
            GET DIAGNOSTICS v_moved = ROW_COUNT;
            v_split := v_moved > 0;
        END IF;
    END IF;
    IF TG_LEVEL = 'STATEMENT' THEN
        -- the end of an UPDATE: every queued row of the face at once (of one group)
        EXECUTE format('SELECT count(*), count(DISTINCT (%s)), array_agg(DISTINCT q.%I::text) FROM %s q',
                       array_to_string(ARRAY(SELECT format('q.%I', k) FROM unnest(v_keycols) AS k), ', '), v_kc, v_queue)
           INTO v_count, v_distinct, v_keys;
        IF v_count = 0 THEN
            RETURN NULL;
        END IF;
        IF v_distinct <> v_count THEN
            RAISE EXCEPTION 'one statement changed a row of %.% twice', TG_TABLE_SCHEMA, TG_TABLE_NAME
                USING ERRCODE = 'cardinality_violation', HINT = 'change each row of a versioned view once in a statement';
        END IF;
    ELSIF TG_OP = 'INSERT' THEN
        EXECUTE format('SELECT ARRAY[($1).%I::text]', v_kc) INTO v_keys USING NEW;
    ELSIF TG_OP = 'DELETE' THEN
        EXECUTE format('SELECT ARRAY[($1).%I::text]', v_kc) INTO v_keys USING OLD;
    ELSE
        EXECUTE format('SELECT ARRAY(SELECT DISTINCT k FROM unnest(ARRAY[($1).%1$I::text, ($2).%1$I::text]) AS k)', v_kc)
           INTO v_keys USING OLD, NEW;
    END IF;
    v_geoids := v_keys::bigint[];

    -- rights, revision, object locks, notes (per row; for the queued rows, by the flush for all at once)
    -- (a class's own table: the face's grants, the class table's, were checked by PostgreSQL for the statement)
    IF v_reg.classname IS NULL THEN
        PERFORM tgsis.check_class_write(v_geoids, CASE WHEN TG_OP = 'DELETE' THEN 'UPDATE, DELETE' ELSE 'UPDATE' END);
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
        EXECUTE format('SELECT (array_agg(%1$s) FILTER (WHERE s.state IS NULL OR s.state = ''absent''))[1], '
                       '       (array_agg(%1$s) FILTER (WHERE s.state IN (''changed'', ''mine'')))[1], '
                       '       coalesce(bool_or(s.state = ''mine''), false) '
                       '  FROM %2$s q LEFT JOIN LATERAL (%3$s) s(state) ON true',
                       format(v_keytext, 'q'), v_queue,
                       -- (a slot gone from a chunk version this transaction wrote: deleted by this statement, 27000, not 40001)
                       format('SELECT CASE WHEN NOT (%1$s) THEN CASE WHEN c.xmin = pg_catalog.xid(pg_catalog.pg_current_xact_id()) '
                              'THEN ''mine'' ELSE ''absent'' END '
                              'WHEN %2$s OPERATOR(pg_catalog.*=) q.tgsis_old THEN ''same'' '
                              'WHEN c.xmin = pg_catalog.xid(pg_catalog.pg_current_xact_id()) THEN ''mine'' ELSE ''changed'' END '
                              'FROM %3$s c WHERE %4$s AND %5$s',
                              format(v_present, 'q'), format(v_decoded, 'q'), v_chunk, format(v_match, 'q'), v_vis))
           INTO v_gone, v_changed, v_mine USING v_set;
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

    -- the chunks' locks (the old key's, the new key's), in key order
    EXECUTE format('SELECT ARRAY(SELECT DISTINCT k FROM unnest(ARRAY[%s]) AS k WHERE k IS NOT NULL ORDER BY k)',
                   concat_ws(', ',
                             CASE WHEN TG_OP <> 'INSERT' THEN format('ROW(%s)::text', array_to_string(
                                 ARRAY(SELECT format('($1).%I', k) FROM unnest(v_keycols[1:cardinality(v_keycols) - 1]) AS k)
                                 || format('($1).%I >> %s', v_cc, v_shift), ', ')) END,
                             CASE WHEN TG_OP <> 'DELETE' THEN format('ROW(%s)::text', array_to_string(
                                 ARRAY(SELECT format('($2).%I', k) FROM unnest(v_keycols[1:cardinality(v_keycols) - 1]) AS k)
                                 || format('($2).%I >> %s', v_cc, v_shift), ', ')) END))
       INTO v_chunks USING OLD, NEW;
    PERFORM pg_advisory_xact_lock(pg_catalog.hashtextextended('tgsis chunk ' || v_table || ' ' || k, v_vid))
       FROM unnest(v_chunks) AS k;
    -- the row the statement read: as it is now (a new snapshot, after the locks)
    IF TG_OP <> 'INSERT' THEN
        EXECUTE v_locate INTO v_state USING v_set, OLD, OLD;
        IF v_state IS NULL OR v_state = 'absent' THEN
            RETURN NULL;  -- deleted meanwhile: nothing to change, as on a plain table
        END IF;
        EXECUTE 'SELECT ' || format(v_keytext, '$1') INTO v_changed USING OLD;
        IF v_state = 'mine' THEN
            RAISE EXCEPTION 'a row (%)=(%) of %.% to be updated was already changed by an operation the current statement triggered',
                    array_to_string(v_keycols, ', '), v_changed, v_sch, v_tname
                USING ERRCODE = 'triggered_data_change_violation',
                      DETAIL = 'A function or trigger the statement ran changed the row after the statement read it.',
                      HINT = 'Change each row of a versioned view once: not both in a statement and in a function or trigger it runs.',
                      TABLE = v_tname, SCHEMA = v_sch;
        ELSIF v_state = 'changed' THEN
            RAISE EXCEPTION 'could not serialize access due to concurrent update of row (%)=(%) of %.% in version %',
                    array_to_string(v_keycols, ', '), v_changed, v_sch, v_tname, quote_literal(tgsis.get_working_version())
                USING ERRCODE = 'serialization_failure',
                      DETAIL = 'A transaction that committed after this statement read the row changed it; '
                               'writing values computed from the old row would undo that change.',
                      HINT = 'Retry the transaction.', TABLE = v_tname, SCHEMA = v_sch;
        END IF;
    END IF;
    -- the new key: a duplicate when it is there
    IF TG_OP <> 'DELETE' THEN
        EXECUTE v_locate INTO v_state USING v_set, NEW, NEW;
        IF v_state IS NOT NULL AND v_state <> 'absent' THEN
            EXECUTE 'SELECT ' || format(v_keytext, '$1') INTO v_changed USING NEW;
            -- the trigger cannot tell whether the statement said ON CONFLICT (PostgreSQL does not pass the
            -- clause to it): named when the client's query has it, as today's views do, never skipped
            IF TG_OP = 'INSERT' AND pg_catalog.current_query() ~* '\mon\s+conflict\M' THEN
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
    END IF;
    IF TG_OP <> 'INSERT' THEN
        EXECUTE format('INSERT INTO %s SELECT ($1).*, true, NULL', v_now) USING OLD;
    END IF;
    IF TG_OP <> 'DELETE' THEN
        EXECUTE format('INSERT INTO %s SELECT ($1).*, false, NULL', v_now) USING NEW;
    END IF;
    PERFORM tgsis.write_chunk_rows(v_table, v_now::regclass);
    EXECUTE format('DELETE FROM %s', v_now);
    IF TG_OP = 'DELETE' THEN
        RETURN OLD;
    END IF;
    RETURN NEW;
END
$$;

REVOKE ALL ON FUNCTION tgsis.chunk_face_write() FROM PUBLIC;

COMMENT ON FUNCTION tgsis.chunk_face_write() IS
    'INSTEAD OF trigger of the face of a chunk table (tgsis.create_chunk_face; TG_ARGV[0] the row table): rights, revision, object locks and notes as today''s versioned views'' triggers, the chunk''s lock, the slot compared with the row read (40001, 27000), 23505 for a visible key, written through tgsis.write_chunk_rows; UPDATEs keeping the key queued and written after the statement';
