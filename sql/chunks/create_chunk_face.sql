-- tgsis.create_chunk_face(table, view): the relational face of a chunk table, a view with the row table's columns and name.
-- docs/storage.md, "The relational face: views with today's names": once a
-- model table is stored in chunks, tgsis.<table> is this view over the
-- visible chunk versions of tgsis.<table>_chunk, with exactly the row table's
-- columns (names, types, order, comments), decoded as tgsis.create_chunk_view
-- decodes them. Versioned storage (tgsis.versioned_tables): the visibility
-- test of today's versioned views (tgsis.versioned_view_source: the session's
-- viewing set, get_revisions in scalar subqueries so that it runs once per
-- query); unversioned storage: every chunk (revision 0); which of the two is
-- decided each time the view is read (versioning may be enabled later). The view reads the
-- chunk table as its owner (the storage's), whom row-level security spares,
-- so it applies the class rights filter of the model tables itself, as a
-- security barrier (tgsis.create_versioned_view does the same). Grants: those
-- of today's relation tgsis.<table> when it exists (the view or table the
-- face will replace), else the storage's. Writes: an INSTEAD OF row trigger
-- keeping each row, the face's own function generated here with static SQL
-- (<schema>.<table>_face_row: a name from the table's, stable across pg_dump/restore;
-- the storage's owner's, SECURITY DEFINER, search_path pinned, revoked from PUBLIC;
-- replaced when the face is made again, dropped with the face by the way back
-- into rows) and, after each INSERT, UPDATE or
-- DELETE statement, the flush of the kept rows (tgsis.chunk_face_write: one
-- rewrite per touched chunk), before each statement tgsis.chunk_face_queue's
-- check of the session's table of kept rows and
-- tgsis.chunk_snapshot_check (40001 for a snapshot older than the chunk
-- table's last rewrite, which it sees empty), and for versioned storage the
-- write right's statement check (tgsis.view_write_check) as today's views
-- have it. Reads: once per query tgsis.chunk_snapshot_guard (40001 for a
-- snapshot older than the chunk table's file, which it would read empty).
-- p_view names the view (default: the table's own name, what the storage
-- switch will use; the tests build the face beside today's live table).
-- Not idempotent: TG201 when the view exists (or a user's function <table>_face_row() does). Runs with the caller's rights
-- (tgsis's owner, who owns the storage).
CREATE FUNCTION tgsis.create_chunk_face(p_table text, p_view text DEFAULT NULL)
RETURNS regclass
LANGUAGE plpgsql
VOLATILE
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_reg       record;
    v_geoidcol  text;      -- a shared model table's geoid column: the class rights filter (a class's own table has its grants)
    v_view      text;
    v_chunk     regclass;
    v_storage   regclass;
    v_today     regclass;
    v_versioned boolean;
    v_dec       record;
    v_where     text[] := '{}';
    v_c         record;
    v_acl       record;
    v_face      regclass;
    v_keycols   text[];
    v_rowfn     text;      -- the face's row function, <schema>.<table>_face_row (a stable name: pg_dump/restore)
    v_rows      text;      -- the session's work tables it writes (tgsis.chunk_face_work) and the setting it reads
    v_dels      text;
    v_flag      text;
    v_seq       text;
    v_chunkwhere text[];   -- the guard, visibility and rights filter of a chunk version (no slot test)
    v_arrays    regclass;  -- model 3's node positions as arrays (tgsis.d4dvrtx_arrays), read by model 3's snapshot at t
BEGIN
    v_chunk := tgsis.chunk_table_of(p_table);  -- TG200 / TG100
    SELECT * INTO v_reg FROM tgsis.chunk_registry(p_table) r;
    v_geoidcol := (SELECT t.geoidcolumn FROM tgsis.model_tables t WHERE t.tablename = v_reg.tablename AND v_reg.classname IS NULL);
    v_view := coalesce(p_view, v_reg.tablename);
    IF to_regclass(format('%I.%I', v_reg.schemaname, v_view)) IS NOT NULL THEN
        RAISE EXCEPTION '% exists already', format('%I.%I', v_reg.schemaname, v_view)
            USING ERRCODE = 'TG201', DETAIL = 'The face of a chunk table takes a name no relation has.';
    END IF;
    -- the face's row function takes <table>_face_row: a function of that name must be an earlier face's of this
    -- table (its owner the chunk table's, its comment ours: made again), never a user's (CREATE OR REPLACE would
    -- put the face's body in a user's function, or fail on one of another owner)
    IF EXISTS (SELECT FROM pg_proc p
                WHERE p.pronamespace = (SELECT n.oid FROM pg_namespace n WHERE n.nspname = v_reg.schemaname) AND p.proname = v_reg.tablename || '_face_row'
                  AND p.pronargs = 0
                  AND (p.proowner <> (SELECT c.relowner FROM pg_class c WHERE c.oid = v_chunk)
                       OR coalesce(obj_description(p.oid, 'pg_proc'), '') NOT LIKE 'row-level INSTEAD OF trigger of the face of %')) THEN
        RAISE EXCEPTION 'the function %.% exists already', quote_ident(v_reg.schemaname), quote_ident(v_reg.tablename || '_face_row')
            USING ERRCODE = 'TG201',
                  DETAIL = 'The face of a chunk table takes <table>_face_row for its row trigger function; this one is not a face''s.',
                  HINT = 'rename or drop that function, then store the table in chunks again';
    END IF;
    v_storage := tgsis.row_shape(p_table);  -- the row definition (comments), before or after the switch
    v_today := to_regclass(format('%I.%I', v_reg.schemaname, v_reg.tablename));
    v_versioned := EXISTS (SELECT FROM tgsis.versioned_tables t WHERE t.schemaname = v_reg.schemaname AND t.tablename = v_reg.tablename);
    SELECT * INTO v_dec FROM tgsis.chunk_decode_sql(p_table, 'v') AS d;
    -- today's test (tgsis.versioned_view_source) while the storage is versioned, decided when the view is read:
    -- versioning can be enabled after the face is made (the hostile review found a face made on unversioned
    -- storage showing every chunk version, twice each vertex, once versioning was enabled)
    -- a snapshot older than the chunk table's file (an add's rewrite, a storage switch) would read it empty:
    -- 40001 instead, checked once per query (an InitPlan; tgsis.chunk_snapshot_guard)
    v_where := v_where || format('(SELECT tgsis.chunk_snapshot_guard(%L::regclass))', v_chunk::text);
    v_where := v_where || format('CASE WHEN (SELECT EXISTS (SELECT FROM tgsis.versioned_tables t '
                                 'WHERE t.schemaname = %L AND t.tablename = %L)) '
                                 'THEN %s ELSE true END', v_reg.schemaname, v_reg.tablename,
                                 tgsis.visible_versions('v', '(SELECT tgsis.get_revisions(true))::integer[]'));
    v_chunkwhere := v_where;  -- the chunk versions' test without the slot's (the arrays view below)
    v_where := v_where || v_dec.present;
    IF v_geoidcol IS NOT NULL THEN
        v_where := v_where || tgsis.class_rights_filter(v_geoidcol, 'SELECT', 'v');
        v_chunkwhere := v_chunkwhere || tgsis.class_rights_filter(v_geoidcol, 'SELECT', 'v');
    END IF;
    EXECUTE format('CREATE VIEW %I.%I WITH (security_barrier = true) AS SELECT %s FROM %s v%s '
                   'CROSS JOIN LATERAL unnest(%s) WITH ORDINALITY AS u(%s, o) WHERE %s',
                   v_reg.schemaname, v_view, v_dec.select_list, v_chunk, v_dec.joins, v_dec.arrays, v_dec.aliases, array_to_string(v_where, ' AND '));
    v_face := format('%I.%I', v_reg.schemaname, v_view)::regclass;
    EXECUTE format('COMMENT ON VIEW %s IS %L', v_face,
                   -- one text whether versioned or not: the WHERE above asks at each read, and a table versioned after
                   -- the switch has the face of one switched while versioned (tests/test_storage_default.py)
                   format('%s, stored in chunks (%s, docs/storage.md "The relational face"): the rows of the visible chunk versions '
                          '(those of the session''s version when versioned), '
                          'written through INSTEAD OF triggers (the generated row function <table>_face_row, then tgsis.chunk_face_write per statement)%s',
                          coalesce(obj_description(v_storage, 'pg_class'), tgsis.chunk_relation(p_table, '')), v_chunk,
                          CASE WHEN v_reg.classname IS NULL THEN '; one vertex by key is read fastest by the keyed reads of model 1 (vertex, vertices)'
                               ELSE '' END));
    FOR v_c IN SELECT a.attname, col_description(v_storage, s.attnum) AS note
                 FROM pg_attribute a JOIN pg_attribute s ON s.attrelid = v_storage AND s.attname = a.attname
                WHERE a.attrelid = v_face AND a.attnum > 0 LOOP
        IF v_c.note IS NOT NULL THEN
            EXECUTE format('COMMENT ON COLUMN %s.%I IS %L', v_face, v_c.attname, v_c.note);
        END IF;
    END LOOP;
    -- the grants of today's relation (what the face replaces), else the storage's
    -- (grant options kept: the way back to rows copies the face's grants, tgsis.store_class_in_rows)
    FOR v_acl IN SELECT a.privilege_type, a.grantee, a.is_grantable FROM pg_class c, aclexplode(c.relacl) AS a
                  WHERE c.oid = coalesce(v_today, v_chunk) AND a.grantee <> c.relowner
                    AND a.privilege_type IN ('SELECT', 'INSERT', 'UPDATE', 'DELETE') LOOP
        EXECUTE format('GRANT %s ON %s TO %s%s', v_acl.privilege_type, v_face,
                       CASE WHEN v_acl.grantee = 0 THEN 'PUBLIC' ELSE quote_ident(pg_get_userbyid(v_acl.grantee)) END,
                       CASE WHEN v_acl.is_grantable THEN ' WITH GRANT OPTION' ELSE '' END);
    END LOOP;
    -- each row kept by the face's own row function (static SQL, its plans kept by the session: no statement
    -- planned per row), its session tables made and checked before the statement (tgsis.chunk_face_queue), all of
    -- them checked and written when the statement ends (tgsis.chunk_face_write): one rewrite per touched chunk
    v_keycols := tgsis.chunk_row_key(p_table);
    v_rowfn := format('%I.%I', v_reg.schemaname, v_reg.tablename || '_face_row');
    v_rows := tgsis.chunk_face_work(p_table, 'rows');
    v_dels := tgsis.chunk_face_work(p_table, 'dels');
    v_flag := quote_literal(tgsis.chunk_face_work(p_table, 'deleted'));
    v_seq := quote_literal('pg_temp.tgsis_face_seq');
    EXECUTE format($body$
CREATE OR REPLACE FUNCTION %1$s()
RETURNS trigger
LANGUAGE plpgsql
VOLATILE
SECURITY DEFINER
SET search_path = pg_catalog, pg_temp
AS $f$
DECLARE
    v_s    bigint;
BEGIN
    IF TG_OP = 'INSERT' THEN
        INSERT INTO %2$s VALUES ('I', NEW, NULL, nextval(%4$s));
        RETURN NEW;
    END IF;
    IF TG_OP = 'UPDATE' THEN
        -- a row of a key the statement deleted, or moved away, before: skipped, kept as the event 'S'
        IF current_setting(%5$s, true) = '1' AND EXISTS (SELECT FROM %3$s d WHERE %6$s) THEN
            INSERT INTO %2$s VALUES ('S', NULL, OLD, nextval(%4$s));
            RETURN NULL;
        END IF;
        INSERT INTO %2$s VALUES ('U', NEW, OLD, nextval(%4$s)) RETURNING s INTO v_s;
        IF NOT (%7$s) THEN
            -- its key moved: the old key gone for the rest of the statement
            INSERT INTO %3$s (o, s, m) VALUES (OLD, v_s, true) ON CONFLICT DO NOTHING;
            IF current_setting(%5$s, true) IS DISTINCT FROM '1' THEN
                PERFORM set_config(%5$s, '1', true);  -- (cleared by the flush)
            END IF;
        END IF;
        RETURN NEW;
    END IF;
    -- a row met twice, or of a key deleted or moved away before: skipped, kept as the event 'X'
    INSERT INTO %3$s VALUES (OLD, nextval(%4$s)) ON CONFLICT DO NOTHING;
    IF NOT FOUND THEN
        INSERT INTO %2$s VALUES ('X', NULL, OLD, nextval(%4$s));
        RETURN NULL;
    END IF;
    RETURN OLD;
END
$f$
$body$, v_rowfn, v_rows, v_dels, v_seq, v_flag,
                   array_to_string(ARRAY(SELECT format('(d.o).%1$I = OLD.%1$I', k) FROM unnest(v_keycols) AS k), ' AND '),
                   array_to_string(ARRAY(SELECT format('NEW.%1$I IS NOT DISTINCT FROM OLD.%1$I', k) FROM unnest(v_keycols) AS k),
                                   ' AND '));
    EXECUTE format('REVOKE ALL ON FUNCTION %s() FROM PUBLIC', v_rowfn);
    EXECUTE format('COMMENT ON FUNCTION %s() IS %L', v_rowfn,
                   format('row-level INSTEAD OF trigger of the face of %s (generated by tgsis.create_chunk_face, static SQL): '
                          'keeps each row written, typed, in the transaction''s %s (a DELETE''s in %s, once) for '
                          'tgsis.chunk_face_write, which checks and writes them when the statement ends; '
                          'the tables made before each statement by tgsis.chunk_face_queue', v_chunk, v_rows, v_dels));
    EXECUTE format('CREATE TRIGGER tgsis_chunk_face INSTEAD OF INSERT OR UPDATE OR DELETE ON %s '
                   'FOR EACH ROW EXECUTE FUNCTION %s()', v_face, v_rowfn);
    EXECUTE format('CREATE TRIGGER tgsis_chunk_face_queue BEFORE INSERT OR UPDATE OR DELETE ON %s '
                   'FOR EACH STATEMENT EXECUTE FUNCTION tgsis.chunk_face_queue(%L)', v_face, p_table);
    EXECUTE format('CREATE TRIGGER tgsis_chunk_face_flush AFTER INSERT OR UPDATE OR DELETE ON %s '
                   'FOR EACH STATEMENT EXECUTE FUNCTION tgsis.chunk_face_write(%L)', v_face, p_table);
    -- a snapshot older than the chunk table's last rewrite sees it empty: its writes are refused (40001)
    EXECUTE format('CREATE TRIGGER tgsis_chunk_face_snapshot BEFORE INSERT OR UPDATE OR DELETE ON %s '
                   'FOR EACH STATEMENT EXECUTE FUNCTION tgsis.chunk_snapshot_check(%L)', v_face, v_chunk::text);
    IF v_versioned THEN
        EXECUTE format('CREATE TRIGGER tgsis_versioning_rights BEFORE INSERT OR UPDATE OR DELETE ON %s '
                       'FOR EACH STATEMENT EXECUTE FUNCTION tgsis.view_write_check()', v_face);
    END IF;
    -- model 3's node positions (the switch's face, named <table> or <table>_face, not a test's face beside the live
    -- table under another name): tgsis.d4dvrtx_arrays,
    -- one row per visible chunk version with its arrays as stored, the face's guard, visibility and rights filter,
    -- rows only for a caller who may read the face (asked at each read), SELECT granted to PUBLIC, the face's owner; model 3's snapshot (vertices_at, temporal/) interpolates two instants' aligned chunks slot by slot on it
    -- (evolving_chunk_vertices; docs/storage.md "Snapshots at t"); dropped by tgsis.store_in_rows
    IF coalesce(p_view, v_reg.tablename) IN (v_reg.tablename, v_reg.tablename || '_face') AND v_reg.classname IS NULL
       AND v_reg.tablename = 'd4dvrtx' THEN
        IF to_regclass('tgsis.d4dvrtx_arrays') IS NOT NULL THEN
            RAISE EXCEPTION 'tgsis.d4dvrtx_arrays exists already'
                USING ERRCODE = 'TG201', DETAIL = 'The switch of tgsis.d4dvrtx into chunks makes the view tgsis.d4dvrtx_arrays.',
                      HINT = 'rename or drop that relation, then store the table in chunks again';
        END IF;
        -- the caller's right on the face, asked when read (by name: the face takes the table's name at the switch's end,
        -- and a name in a text makes no dependency): a GRANT or REVOKE on the face reaches the arrays
        EXECUTE format('CREATE VIEW tgsis.d4dvrtx_arrays WITH (security_barrier = true) AS '
                       'SELECT v.geoid, v.timem, v.timet, v.chunk, v.chunk << %s AS base, v.x, v.y, v.z FROM %s v WHERE %s',
                       (SELECT round(log(2, r.chunksize))::integer FROM tgsis.chunk_registry(p_table) r), v_chunk,
                       array_to_string(v_chunkwhere || format('(SELECT coalesce(has_table_privilege(to_regclass(%L), ''SELECT''), false))',
                                                              format('%I.%I', v_reg.schemaname, v_reg.tablename)),
                                       ' AND '));
        v_arrays := 'tgsis.d4dvrtx_arrays'::regclass;
        EXECUTE format('COMMENT ON VIEW %s IS %L', v_arrays,
                       format('model 3''s node positions stored in chunks (%s): one row per visible chunk version (the face''s '
                              'guard, visibility and class rights filter; none for a caller who may not read the face), base the id of its first slot, x, y, z its arrays '
                              '(NULL at a hole); read by model 3''s snapshot at t (vertices_at, evolving_chunk_vertices), made by the switch '
                              'into chunks, dropped by the way back', v_chunk));
        -- readable by PUBLIC: the rows are those of the face the caller may read (the test above, the class rights filter)
        EXECUTE format('GRANT SELECT ON %s TO PUBLIC', v_arrays);
        EXECUTE format('ALTER VIEW %s OWNER TO %I', v_arrays,
                       (SELECT pg_get_userbyid(c.relowner) FROM pg_class c WHERE c.oid = v_chunk));
    END IF;
    EXECUTE format('ALTER VIEW %s OWNER TO %I', v_face,
                   (SELECT pg_get_userbyid(c.relowner) FROM pg_class c WHERE c.oid = v_chunk));
    EXECUTE format('ALTER FUNCTION %s() OWNER TO %I', v_rowfn,
                   (SELECT pg_get_userbyid(c.relowner) FROM pg_class c WHERE c.oid = v_chunk));
    RETURN v_face;
END
$$;

REVOKE ALL ON FUNCTION tgsis.create_chunk_face(text, text) FROM PUBLIC;

COMMENT ON FUNCTION tgsis.create_chunk_face(text, text) IS
    'create the view tgsis.<p_view or p_table> over the visible chunk versions of tgsis.<table>_chunk with exactly the row table''s columns (today''s visibility when versioned, the class rights filter, security_barrier, the grants of today''s relation), written through INSTEAD OF triggers (each row kept by the face''s generated row function <table>_face_row, static SQL, in tables tgsis.chunk_face_queue makes before the statement, written per statement by tgsis.chunk_face_write); TG200 without a chunk table, TG201 when the view exists or a function <table>_face_row() is not an earlier face''s';
