-- tgsis.merge_write_instant_row(table, geoid, key columns, key, columns, merged, version's): write one per-instant feature property row of a psql merge; rows written.
-- The per-instant feature property rows (<class>_pros) of the psql merges of
-- temporal surfaces (tgsis.merge_instants_by_slice, model 2, keyed _times;
-- tgsis.merge_periods_by_slice, model 3, keyed _timem, _timet), written as
-- tgsis.db._state_write._write_instant_rows writes them in Python: per
-- instant (p_key: the values of the key columns p_keys) a DELETE, INSERT or
-- UPDATE of the class's view, which its trigger writes: a row of the working
-- revision p_revision changed in place, any other closed there and written
-- anew. p_merged is the merged row (NULL: none), p_mine the version's (NULL:
-- none), both the values of p_cols as text. The right the Python client's
-- statement needs is asked first (tgsis.check_merge_table_write, 42501). The
-- caller has the session in the version's working revision; the column types
-- come from the table.
CREATE FUNCTION tgsis.merge_write_instant_row(p_table tgsis.versioned_tables, p_geoid bigint, p_keys text[], p_key text[],
                                              p_cols text[], p_merged text[], p_mine text[], p_revision integer,
                                              p_workingset integer[])
RETURNS bigint
LANGUAGE plpgsql
VOLATILE
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_rel   regclass := format('%I.%I', p_table.schemaname, p_table.tablename)::regclass;
    v_k     integer := cardinality(p_keys);
    v_where text;
    v_cols  text;
    v_casts text;
    v_sets  text;
    v_count bigint := 0;
BEGIN
    IF p_merged IS NOT DISTINCT FROM p_mine THEN
        RETURN 0;
    END IF;
    PERFORM tgsis.check_merge_table_write(p_table, CASE WHEN p_mine IS NULL THEN 'INSERT'
                                                        WHEN p_merged IS NULL THEN 'DELETE' ELSE 'UPDATE' END, p_geoid);
    -- the row's key: _geoid = $1[1], then the key columns ($1[2] ...), the values after them
    SELECT string_agg(format(' AND v.%I = $1[%s]::%s', u.c, u.o + 1, format_type(a.atttypid, a.atttypmod)), '' ORDER BY u.o)
      INTO v_where
      FROM unnest(p_keys) WITH ORDINALITY AS u(c, o)
      JOIN pg_catalog.pg_attribute a ON a.attrelid = v_rel AND a.attname = u.c AND NOT a.attisdropped;
    v_where := 'v._geoid = $1[1]::bigint' || v_where;
    SELECT string_agg(format('%I', u.c), ', ' ORDER BY u.o),
           string_agg(format('$1[%s]::%s', u.o + v_k + 1, format_type(a.atttypid, a.atttypmod)), ', ' ORDER BY u.o),
           string_agg(format('%I = $1[%s]::%s', u.c, u.o + v_k + 1, format_type(a.atttypid, a.atttypmod)), ', ' ORDER BY u.o)
      INTO v_cols, v_casts, v_sets
      FROM unnest(p_cols) WITH ORDINALITY AS u(c, o)
      JOIN pg_catalog.pg_attribute a ON a.attrelid = v_rel AND a.attname = u.c AND NOT a.attisdropped;
    IF p_merged IS NOT NULL AND p_mine IS NOT NULL THEN  -- in place in the working revision
        SELECT r[1]::bigint INTO v_count FROM tgsis.storage_run(p_table, true, format(
            'UPDATE %I.%I v SET %s WHERE %s AND v.revision = $4 AND NOT (v.lastrevs && $2)',
            p_table.schemaname, p_table.tablename || '_ver', v_sets, v_where),
            p_1 => ARRAY[p_geoid::text] || p_key || p_merged, p_2 => p_workingset, p_4 => p_revision) AS r;
    END IF;
    IF v_count = 0 AND p_mine IS NOT NULL THEN  -- the version's row goes (closed, or gone if its revision's)
        SELECT r[1]::bigint INTO v_count FROM tgsis.storage_run(p_table, true, format(
            'DELETE FROM %I.%I v WHERE %s AND v.revision = $4', p_table.schemaname, p_table.tablename || '_ver', v_where),
            p_1 => ARRAY[p_geoid::text] || p_key, p_4 => p_revision) AS r;
        IF v_count = 0 THEN
            SELECT r[1]::bigint INTO v_count FROM tgsis.storage_run(p_table, true, format(
                'UPDATE %I.%I v SET lastrevs = v.lastrevs || $4 WHERE %s AND v.revision = ANY ($2) AND NOT (v.lastrevs && $2)',
                p_table.schemaname, p_table.tablename || '_ver', v_where),
                p_1 => ARRAY[p_geoid::text] || p_key, p_2 => p_workingset, p_4 => p_revision) AS r;
            PERFORM tgsis.note_changed_objects(p_table.schemaname, p_table.tablename, p_revision, ARRAY[p_geoid::text]);
        END IF;
        IF p_merged IS NOT NULL THEN
            v_count := 0;  -- (an UPDATE of the view: one row)
        END IF;
    END IF;
    IF p_merged IS NOT NULL AND v_count = 0 THEN
        SELECT r[1]::bigint INTO v_count FROM tgsis.storage_run(p_table, true, format(
            'INSERT INTO %I.%I (_geoid, %s, %s, revision) SELECT $1[1]::bigint, %s, %s, $4',
            p_table.schemaname, p_table.tablename || '_ver',
            (SELECT string_agg(format('%I', c), ', ' ORDER BY o) FROM unnest(p_keys) WITH ORDINALITY AS u(c, o)), v_cols,
            (SELECT string_agg(format('$1[%s]::%s', u.o + 1, format_type(a.atttypid, a.atttypmod)), ', ' ORDER BY u.o)
               FROM unnest(p_keys) WITH ORDINALITY AS u(c, o)
               JOIN pg_catalog.pg_attribute a ON a.attrelid = v_rel AND a.attname = u.c AND NOT a.attisdropped),
            v_casts),
            p_1 => ARRAY[p_geoid::text] || p_key || p_merged, p_4 => p_revision) AS r;
    END IF;
    RETURN v_count;
END
$$;

-- internal to the psql merges (their owner's code), not executable by PUBLIC (tests/test_function_grants.py)
REVOKE ALL ON FUNCTION tgsis.merge_write_instant_row(tgsis.versioned_tables, bigint, text[], text[], text[], text[], text[], integer, integer[]) FROM PUBLIC;

COMMENT ON FUNCTION tgsis.merge_write_instant_row(tgsis.versioned_tables, bigint, text[], text[], text[], text[], text[], integer, integer[]) IS
    'one per-instant feature property row of a psql merge of a temporal surface, written as the Python writer writes it (an UPDATE in place, or the version''s row closed and the merged one written), the right asked first; returns the rows written';
