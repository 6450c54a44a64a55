-- tgsis.write_property_rows(table, geoid, deleted, rows): write some property rows of one object of a class's property table in chunks, each touched chunk once.
-- docs/storage.md, "The bulk paths of property chunks": the check-in by
-- difference and the merges that write a state (tgsis.db.checkin,
-- tgsis.db._state_write) wrote a class's property rows through the face of
-- tgsis.store_class_in_chunks: a DELETE of the rows that go or change, then a
-- COPY of the new and changed rows, which the face's trigger
-- (tgsis.chunk_face_write) writes row by row, one chunk rewrite per row
-- (a 1 % edit of a 1M-vertex class: 10,000 rewrites). Here the edit is given
-- at once: p_deleted the ids that go (and the ids whose row changes: a row of
-- p_rows replaces the row of its id), p_rows the new and changed rows as an
-- array of the face's row type; every touched chunk is rewritten once by the
-- one writer of chunk contents (tgsis.write_chunk_rows: in place when the
-- visible version is the working revision's, else closed and written anew in
-- it; every chunk version locked in key order, in READ COMMITTED the version
-- a concurrent writer committed is the one merged into, in REPEATABLE READ a
-- chunk changed after the snapshot is 40001), versioned or not.
-- The checks are the face's for the same statements, for the whole set:
-- the calling role's INSERT on the face for rows written, DELETE for rows
-- that go or change (42501); versioned: the version's write right and TG301
-- (tgsis.write_revision), the object not locked by another version (TG303);
-- else TG305 outside DEFAULT's working revision (tgsis.plain_write_check); a
-- written id that is not among p_deleted and is present now is 23505 (as the
-- face's INSERT of a present key); rows of another object, or an id twice,
-- TG100; a NULL into a NOT NULL property and CHECKs as tgsis.write_chunk_rows
-- refuses them. The object's write lock is taken exclusively
-- (tgsis.object_write_lock: the face's writers hold it shared, so no face
-- write of the object is in flight and none starts before the commit), and
-- the object is noted as changed in the working revision
-- (tgsis.record_changed_objects) when a chunk was written, as
-- tgsis.swap_object_chunks notes it (an edit that leaves every chunk the same,
-- such as the delete of an id with no row, notes nothing). SECURITY DEFINER:
-- the chunk table is written by its owner only. Returns the chunks written.
CREATE FUNCTION tgsis.write_property_rows(p_table text, p_geoid bigint, p_deleted bigint[], p_rows anyarray)
RETURNS bigint
LANGUAGE plpgsql
VOLATILE
SECURITY DEFINER
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_reg       record;
    v_chunk     regclass;
    v_face      regclass;
    v_role      name := tgsis.calling_role();
    v_keys      text[] := ARRAY[p_geoid::text];
    v_n         bigint := coalesce(cardinality(p_rows), 0);
    v_d         bigint := coalesce(cardinality(p_deleted), 0);
    v_versioned boolean;
    v_w         integer;
    v_set       integer[];
    v_tab       text;
    v_cols      text;
    v_bad       record;
    v_present   bigint;
    v_fresh     bigint[];
    v_written   bigint;
BEGIN
    SELECT * INTO v_reg FROM tgsis.chunk_registry(p_table) r WHERE r.classname IS NOT NULL;
    v_face := CASE WHEN FOUND THEN to_regclass(format('%I.%I', v_reg.schemaname, v_reg.tablename)) END;
    IF v_face IS NULL OR NOT tgsis.stored_in_chunks(v_reg.schemaname, v_reg.tablename) THEN
        RAISE EXCEPTION 'the properties of % are not stored in chunks', coalesce(p_table, 'NULL')
            USING ERRCODE = 'TG200',
                  DETAIL = 'Only the property table of a STATIC class switched by tgsis.store_class_in_chunks has property chunks.',
                  HINT = 'write the rows into the property table';
    END IF;
    v_chunk := to_regclass(tgsis.chunk_relation(p_table, '_chunk'));
    IF pg_typeof(p_rows) <> (SELECT t.typarray FROM pg_type t JOIN pg_class c ON c.reltype = t.oid WHERE c.oid = v_face)::regtype THEN
        RAISE EXCEPTION 'the rows given are %, not an array of %', pg_typeof(p_rows), v_face
            USING ERRCODE = 'TG100', HINT = format('pass array_agg(ROW(...)::%s) of the rows', v_face);
    END IF;
    IF p_geoid IS NULL OR array_position(p_deleted, NULL) IS NOT NULL THEN
        RAISE EXCEPTION 'the rows to write into % name no object, or a NULL id to delete', v_face
            USING ERRCODE = 'TG100', DETAIL = format('geoid %s; %s ids to delete.', coalesce(p_geoid::text, 'NULL'), v_d),
                  HINT = 'give the object and the ids that go';
    END IF;
    IF v_n + v_d = 0 THEN
        RETURN 0;
    END IF;

    -- the rights of the face's statements: INSERT for the rows written, DELETE for those that go or change
    IF (v_n > 0 AND NOT has_table_privilege(v_role, v_face, 'INSERT'))
       OR (v_d > 0 AND NOT has_table_privilege(v_role, v_face, 'DELETE')) THEN
        RAISE EXCEPTION 'permission denied for view %', v_face
            USING ERRCODE = 'insufficient_privilege',
                  DETAIL = format('Role %s: rows written need INSERT on %s, rows that go or change DELETE.', quote_ident(v_role), v_face),
                  HINT = 'its owner can GRANT INSERT, DELETE on it';
    END IF;
    v_versioned := EXISTS (SELECT FROM tgsis.versioned_tables t WHERE t.schemaname = v_reg.schemaname AND t.tablename = v_reg.tablename);
    IF v_versioned THEN
        SELECT w.revision, w.revisions INTO v_w, v_set FROM tgsis.write_revision() AS w;  -- TG002, TG301 before any lock
        PERFORM tgsis.check_objects_unlocked('feature', v_keys);  -- TG303
    ELSE
        PERFORM tgsis.plain_write_check(v_reg.schemaname, v_reg.tablename);  -- TG305
        v_w := 0;
        v_set := ARRAY[0];
    END IF;
    PERFORM tgsis.object_write_lock('feature', v_keys);

    -- the rows, in a temporary table of tgsis's owner (tgsis.write_chunk_rows reads it in several statements)
    v_tab := format('pg_temp.%I', 'tgsis_property_rows_' || v_chunk::oid);
    IF to_regclass(v_tab) IS NOT NULL THEN
        IF (SELECT c.relowner FROM pg_class c WHERE c.oid = to_regclass(v_tab))
           <> (SELECT r.oid FROM pg_roles r WHERE r.rolname = current_user) THEN
            RAISE EXCEPTION 'the session''s table % was not made by tgsis.write_property_rows', v_tab
                USING ERRCODE = 'insufficient_privilege', HINT = 'drop the temporary table and write again';
        END IF;
        EXECUTE format('DROP TABLE %s', v_tab);  -- (of the columns before a property was added, renamed or dropped)
    END IF;
    EXECUTE format('CREATE TEMP TABLE %s ON COMMIT DROP AS SELECT *, false AS _delete FROM %s WITH NO DATA',
                   v_tab, tgsis.row_shape(p_table));
    SELECT string_agg(quote_ident(a.attname), ', ' ORDER BY a.attnum) INTO v_cols
      FROM pg_attribute a WHERE a.attrelid = tgsis.row_shape(p_table) AND a.attnum > 0 AND NOT a.attisdropped;
    EXECUTE format('INSERT INTO %s (%s, _delete) SELECT %s, false FROM unnest($1) r', v_tab, v_cols,
                   (SELECT string_agg('r.' || c, ', ') FROM unnest(string_to_array(v_cols, ', ')) AS c))
       USING p_rows;
    EXECUTE format('SELECT r._geoid, r._idx, count(*) OVER () AS n FROM %s r WHERE r._geoid IS DISTINCT FROM $1 LIMIT 1', v_tab)
       INTO v_bad USING p_geoid;
    IF v_bad.n IS NOT NULL THEN
        RAISE EXCEPTION 'a row to write into % is not of object %: object %, id %', v_face, p_geoid,
                        coalesce(v_bad._geoid::text, 'NULL'), coalesce(v_bad._idx::text, 'NULL')
            USING ERRCODE = 'TG100', DETAIL = format('%s row(s) of another object; nothing was written.', v_bad.n),
                  HINT = 'write the rows of one object per call';
    END IF;
    -- a written id that stays (not among p_deleted) and is present now: the face's INSERT of a present key (23505);
    -- only the chunks holding those ids are decoded (the check-in's new ids are above every id the object had)
    EXECUTE format('SELECT array_agg(i) FROM (SELECT r._idx AS i FROM %s r EXCEPT SELECT d FROM unnest($1) AS d) s', v_tab)
       INTO v_fresh USING p_deleted;
    IF v_fresh IS NOT NULL THEN
        EXECUTE format('SELECT min(f._idx) FROM %s f WHERE f._geoid = $1 AND f._idx = ANY ($3) '
                       'AND (f.revision = ANY ($2)) IS TRUE AND NOT (f.lastrevs && $2)',
                       tgsis.storage_row_versions(v_reg.schemaname, v_reg.tablename, v_fresh))
           INTO v_present USING p_geoid, v_set, v_fresh;
        IF v_present IS NOT NULL THEN
            RAISE EXCEPTION 'duplicate key value violates unique constraint "%"', v_reg.tablename || '_pkey'
                USING ERRCODE = 'unique_violation',
                      DETAIL = format('Key (_geoid, _idx)=(%s, %s) already exists%s; nothing was written.', p_geoid, v_present,
                                      CASE WHEN v_versioned THEN ' in version ' || quote_literal(tgsis.get_working_version()) ELSE '' END),
                      HINT = 'give the ids whose rows change among the ids deleted',
                      CONSTRAINT = v_reg.tablename || '_pkey', TABLE = v_reg.tablename, SCHEMA = v_reg.schemaname;
        END IF;
    END IF;
    -- the deletes of the ids not written again (a row written replaces the row of its id)
    EXECUTE format('INSERT INTO %1$s (_geoid, _idx, _delete) SELECT $1, d.i, true '
                   'FROM (SELECT d AS i FROM unnest($2) AS d EXCEPT SELECT r._idx FROM %1$s r) d', v_tab)
       USING p_geoid, p_deleted;
    v_written := tgsis.write_chunk_rows(p_table, v_tab::regclass);
    EXECUTE format('DROP TABLE %s', v_tab);
    -- noted only when a chunk was written, as tgsis.swap_object_chunks (the client's path) notes it: an edit
    -- that leaves every chunk as it was (a delete of an id that has no row, as a merge's renumbered new vertex
    -- without properties gives) changes nothing, and the next merge or conflict check has nothing to read there
    IF v_w <> 0 AND v_written > 0 THEN
        PERFORM tgsis.record_changed_objects(v_reg.schemaname, v_reg.tablename, v_keys);
    END IF;
    RETURN v_written;
END
$$;

REVOKE ALL ON FUNCTION tgsis.write_property_rows(text, bigint, bigint[], anyarray) FROM PUBLIC;
GRANT EXECUTE ON FUNCTION tgsis.write_property_rows(text, bigint, bigint[], anyarray) TO tgsis_reader;

COMMENT ON FUNCTION tgsis.write_property_rows(text, bigint, bigint[], anyarray) IS
    'write some property rows of one object of a class''s property table stored in chunks (tgsis.store_class_in_chunks), versioned or not, for the calling role: ids that go or change, and the new and changed rows as an array of the face''s row type; the face''s checks for the whole set (INSERT/DELETE on the face: 42501, TG002/TG301/TG303 or TG305, 23505 for a present id written without its delete), the object''s write lock, every touched chunk rewritten once by tgsis.write_chunk_rows; returns the chunks written';
