-- tgsis.merge_write_keyed_rows(table, object key, geoid, key columns, gone, fresh, revision, working set, refusal, hint): one table's part of a psql merge's keyed difference; rows written.
-- The writer the psql merges of temporal surfaces share (tgsis.merge_instants_by_slice,
-- model 2; tgsis.merge_periods_by_slice, model 3), as tgsis.db._state_write._write_table_difference
-- writes one table in Python: the rows of the keys p_gone (the version's rows
-- whose key is gone from the merge or whose bits differ) are closed in the
-- version's working revision p_revision (a row of that revision removed, any
-- other it sees given the revision in lastrevs, its object noted), then the
-- rows p_fresh (the merge's new and differing rows) are inserted into the
-- storage with that revision, as the Python client COPYs them there. A key is
-- the object key (p_okey = p_geoid) and the columns p_keys; p_gone holds the
-- keys' values one row after the other (cardinality(p_keys) values each),
-- p_fresh the key values then every other column of the table in its
-- order, one row after the other, as text. The rights the Python merge meets
-- are asked first (tgsis.check_merge_table_write: DELETE on the view, INSERT
-- on the storage), 42501 and nothing written otherwise; then, with p_refused,
-- fresh rows without a value for a column other than a float one (a property
-- row merged from a vertex without one) are refused (TG302, p_refused and
-- p_hint worded by the caller), as the Python writer refuses them. The caller has the
-- session in the version's working revision; the key and value types come
-- from the table's columns, never from the caller.
CREATE FUNCTION tgsis.merge_write_keyed_rows(p_table tgsis.versioned_tables, p_okey text, p_geoid bigint, p_keys text[],
                                             p_gone text[], p_fresh text[], p_revision integer, p_workingset integer[],
                                             p_refused text DEFAULT NULL, p_hint text DEFAULT NULL)
RETURNS bigint
LANGUAGE plpgsql
VOLATILE
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_rel     regclass := format('%I.%I', p_table.schemaname, p_table.tablename)::regclass;
    v_k       integer := cardinality(p_keys);
    v_width   integer;
    v_keyset  text;
    v_on      text;
    v_cols    text;
    v_casts   text;
    v_count   bigint;
    v_written bigint := 0;
    v_tab     text;
    v_shape   text;
    -- the table as the chunk layer names it (tgsis.chunk_registry): a model table bare, a class's schema-qualified
    v_name    text := CASE WHEN p_table.schemaname = 'tgsis' THEN p_table.tablename
                           ELSE format('%I.%I', p_table.schemaname, p_table.tablename) END;
BEGIN
    -- the keys of $1 (its first element the object) as a relation k (k1, ..., kn) of the columns' types
    SELECT format('(SELECT DISTINCT %s FROM generate_series(0, (cardinality($1) - 1) / %s - 1) AS g(i)) AS k',
                  string_agg(format('($1[2 + g.i * %s + %s])::%s AS %I', v_k, u.o - 1,
                                    format_type(a.atttypid, a.atttypmod), 'k' || u.o), ', ' ORDER BY u.o), v_k),
           string_agg(format('v.%I = k.%I', u.c, 'k' || u.o), ' AND ' ORDER BY u.o)
      INTO v_keyset, v_on
      FROM unnest(p_keys) WITH ORDINALITY AS u(c, o)
      JOIN pg_catalog.pg_attribute a ON a.attrelid = v_rel AND a.attname = u.c AND NOT a.attisdropped;
    IF tgsis.stored_in_chunks(p_table.schemaname, p_table.tablename) THEN
        -- stored in chunks (model 2's time tables, a temporal class's property table): the same rights asked, then the keys that go (those not written
        -- again) and the rows written as one set by the writer of chunk contents, in the session's working
        -- revision (the version's: the caller put the session there), each touched chunk once
        IF cardinality(p_gone) > 0 THEN
            PERFORM tgsis.check_merge_table_write(p_table, 'DELETE', p_geoid);
        END IF;
        IF cardinality(p_fresh) > 0 THEN
            -- (on the face, not the chunk table: the right the Python merge's tgsis.insert_chunk_rows asks)
            PERFORM tgsis.check_merge_table_write(p_table, 'INSERT', p_geoid);
        END IF;
        IF coalesce(cardinality(p_gone), 0) + coalesce(cardinality(p_fresh), 0) = 0 THEN
            RETURN 0;
        END IF;
        SELECT count(*)::integer,
               string_agg(format('%I', c.attname), ', ' ORDER BY c.o),
               string_agg(format('($1[2 + g.i * %%1$s + %s])::%s', c.o - 1, format_type(c.atttypid, c.atttypmod)), ', ' ORDER BY c.o)
          INTO v_width, v_cols, v_casts
          FROM (SELECT a.attname, a.atttypid, a.atttypmod,
                       row_number() OVER (ORDER BY coalesce(array_position(p_keys, a.attname::text), v_k + 1), a.attnum) AS o
                  FROM pg_catalog.pg_attribute a
                 WHERE a.attrelid = v_rel AND a.attnum > 0 AND NOT a.attisdropped AND a.attname <> p_okey) AS c;
        -- (one table of the session's for every object and merge: a table made and dropped per object keeps a lock
        -- until the transaction ends, and a merge of many objects would run out of the shared lock table)
        v_tab := format('pg_temp.%I', 'tgsis_merge_rows_' || CASE WHEN p_table.schemaname = 'tgsis' THEN p_table.tablename
                                                                   ELSE left(md5(v_name), 16) END);
        IF to_regclass(v_tab) IS NULL THEN
            EXECUTE format('SELECT tgsis.%I($1)::text', 'row_shape') INTO v_shape USING v_name;
            EXECUTE format('CREATE TEMP TABLE %s AS SELECT *, false AS _delete FROM %s WITH NO DATA', v_tab, v_shape);
        ELSIF (SELECT c.relowner FROM pg_class c WHERE c.oid = to_regclass(v_tab))
              <> (SELECT r.oid FROM pg_roles r WHERE r.rolname = current_user) THEN
            RAISE EXCEPTION 'the session''s table % was not made by tgsis.merge_write_keyed_rows', v_tab
                USING ERRCODE = 'insufficient_privilege', HINT = 'drop the temporary table and merge again';
        ELSE
            EXECUTE format('TRUNCATE %s', v_tab);
        END IF;
        IF cardinality(p_fresh) > 0 THEN
            EXECUTE format('INSERT INTO %s (%I, %s, _delete) SELECT $1[1]::bigint, %s, false '
                           'FROM generate_series(0, (cardinality($1) - 1) / %s - 1) AS g(i)',
                           v_tab, p_okey, v_cols, format(v_casts, v_width), v_width)
              USING ARRAY[p_geoid::text] || p_fresh;
            GET DIAGNOSTICS v_count = ROW_COUNT;
            v_written := v_written + v_count;
        END IF;
        IF cardinality(p_gone) > 0 THEN
            EXECUTE format('INSERT INTO %s (%I, %s, _delete) SELECT $1[1]::bigint, %s, true FROM %s '
                           'WHERE NOT EXISTS (SELECT FROM %s v WHERE v.%I = $1[1]::bigint AND %s)',
                           v_tab, p_okey, (SELECT string_agg(format('%I', u.c), ', ' ORDER BY u.o) FROM unnest(p_keys) WITH ORDINALITY AS u(c, o)),
                           (SELECT string_agg(format('k.%I', 'k' || u.o), ', ' ORDER BY u.o) FROM unnest(p_keys) WITH ORDINALITY AS u(c, o)),
                           v_keyset, v_tab, p_okey, v_on)
              USING ARRAY[p_geoid::text] || p_gone;
            v_written := v_written + cardinality(p_gone) / v_k;
        END IF;
        EXECUTE format('SELECT tgsis.%I($1, $2)', 'write_chunk_rows') INTO v_count USING v_name, v_tab::regclass;
        IF v_count > 0 THEN
            PERFORM tgsis.note_changed_objects(p_table.schemaname, p_table.tablename, p_revision, ARRAY[p_geoid::text]);
        END IF;
        EXECUTE format('TRUNCATE %s', v_tab);
        RETURN v_written;
    END IF;
    IF cardinality(p_gone) > 0 THEN
        PERFORM tgsis.check_merge_table_write(p_table, 'DELETE', p_geoid);
        SELECT r[1]::bigint INTO v_count FROM tgsis.storage_run(p_table, true, format(
            'DELETE FROM %I.%I v USING %s WHERE v.%I = $1[1]::bigint AND v.revision = $4 AND %s',
            p_table.schemaname, p_table.tablename || '_ver', v_keyset, p_okey, v_on),
            p_1 => ARRAY[p_geoid::text] || p_gone, p_4 => p_revision) AS r;
        v_written := v_written + v_count;
        SELECT r[1]::bigint INTO v_count FROM tgsis.storage_run(p_table, true, format(
            'UPDATE %I.%I v SET lastrevs = v.lastrevs || $4 FROM %s
              WHERE v.%I = $1[1]::bigint AND v.revision = ANY ($3) AND NOT (v.lastrevs && $3) AND %s',
            p_table.schemaname, p_table.tablename || '_ver', v_keyset, p_okey, v_on),
            p_1 => ARRAY[p_geoid::text] || p_gone, p_3 => p_workingset, p_4 => p_revision) AS r;
        IF v_count > 0 THEN
            PERFORM tgsis.note_changed_objects(p_table.schemaname, p_table.tablename, p_revision, ARRAY[p_geoid::text]);
        END IF;
        v_written := v_written + v_count;
    END IF;
    IF cardinality(p_fresh) = 0 THEN
        RETURN v_written;
    END IF;
    PERFORM tgsis.check_merge_table_write(p_table, 'INSERT', p_geoid, true);  -- (the Python client COPYs them there)
    IF p_refused IS NOT NULL AND EXISTS (SELECT FROM unnest(p_fresh) AS f WHERE f IS NULL)
       AND EXISTS (SELECT FROM pg_catalog.pg_attribute a
                    WHERE a.attrelid = v_rel AND a.attnum > 0 AND NOT a.attisdropped AND a.attname <> p_okey
                      AND a.attname <> ALL (p_keys) AND a.atttypid NOT IN ('real'::regtype, 'double precision'::regtype)) THEN
        RAISE EXCEPTION '%: its merged rows cannot be written: some property rows have no value for an integer or boolean property',
                p_refused
            USING ERRCODE = 'TG302', HINT = p_hint;
    END IF;
    -- the columns: the keys, then the others in the table's order
    SELECT count(*)::integer,
           string_agg(format('%I', c.attname), ', ' ORDER BY c.o),
           string_agg(format('($1[2 + g.i * %%1$s + %s])::%s', c.o - 1, format_type(c.atttypid, c.atttypmod)), ', ' ORDER BY c.o)
      INTO v_width, v_cols, v_casts
      FROM (SELECT a.attname, a.atttypid, a.atttypmod,
                   row_number() OVER (ORDER BY coalesce(array_position(p_keys, a.attname::text), v_k + 1), a.attnum) AS o
              FROM pg_catalog.pg_attribute a
             WHERE a.attrelid = v_rel AND a.attnum > 0 AND NOT a.attisdropped AND a.attname <> p_okey) AS c;
    SELECT r[1]::bigint INTO v_count FROM tgsis.storage_run(p_table, true, format(
        'INSERT INTO %I.%I (%I, %s, revision) SELECT $1[1]::bigint, %s, $4 FROM generate_series(0, (cardinality($1) - 1) / %s - 1) AS g(i)',
        p_table.schemaname, p_table.tablename || '_ver', p_okey, v_cols, format(v_casts, v_width), v_width),
        p_1 => ARRAY[p_geoid::text] || p_fresh, p_4 => p_revision) AS r;
    RETURN v_written + v_count;
END
$$;

-- internal to the psql merges (their owner's code), not executable by PUBLIC (tests/test_function_grants.py)
REVOKE ALL ON FUNCTION tgsis.merge_write_keyed_rows(tgsis.versioned_tables, text, bigint, text[], text[], text[], integer, integer[], text, text) FROM PUBLIC;

COMMENT ON FUNCTION tgsis.merge_write_keyed_rows(tgsis.versioned_tables, text, bigint, text[], text[], text[], integer, integer[], text, text) IS
    'one table''s part of a psql merge''s keyed difference, as the Python writer writes it: the rows of the gone keys closed in the version''s working revision, the fresh rows inserted into the storage with it, the rights asked first; returns the rows written';
