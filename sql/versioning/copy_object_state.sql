-- tgsis.copy_object_state(objectclass, keys, from_set, to_set, revision): make objects look in to_set as they look in from_set.
-- For every table of the class, the rows of the objects visible in to_set but
-- not in from_set are closed with revision (deleted when written in it), and
-- the rows visible in from_set but not in to_set are copied with revision.
-- Rows visible in both are left alone: unchanged rows are never copied.
-- Nor is a row whose content to_set already holds: when a row key (the
-- table's keycolumns) has exactly one row visible only in to_set and one
-- visible only in from_set, and the two hold the same content
-- (tgsis.same_row_sql: exactly, value for value), the first stays and the
-- second is not copied. So a merge does not write again into the parent the
-- parent's own edits the child holds too (a merge by region writes the merged
-- mesh into the child first: it holds them all), nor rows one side deleted
-- and inserted again as they were; what it writes is the child's change.
-- The match is read by key (the storage's primary key) for the candidate
-- rows only: the cost follows the change, not the object's size.
-- The common step of merge (child's state into the parent) and refresh.
-- On a model table stored in chunks the rows are chunk versions (tgsis.<table>_chunk,
-- keyed by (geoid, chunk): tgsis.storage_key), closed and copied whole: the unit of
-- a conflict is the object, so copying one side's chunks is copying its rows
-- (docs/storage.md, "Versioning of chunks").
-- Every statement also states what both kinds of rows share, in a form the
-- storage's revision indexes serve (tgsis.create_revision_indexes): a row
-- visible in one set and not the other was written in a revision of their
-- symmetric difference, or closed in one (revclosed, lastrevs meeting it).
-- Redundant, so the rows acted on are the same; but the statements read the
-- rows of the change instead of filtering all the objects' rows.
-- The objects are noted as changed in revision (tgsis.revision_objects) in the
-- tables where rows were written; an object with nothing written looks in
-- to_set as in from_set already and is not noted.
-- Returns the rows written (closed, deleted and copied): rows of row storage
-- and chunk versions of chunk storage alike. The chunk versions among them are
-- also added to the transaction's setting tgsis.chunk_versions_written (set
-- LOCAL; a value that is not a count restarts it from 0), so that a caller who
-- set it to 0 before reads the two units apart (tgsis.db.merging.MergeResult).
CREATE FUNCTION tgsis.copy_object_state(
    p_objectclass text,
    p_keys        text[],
    p_from        integer[],
    p_to          integer[],
    p_revision    integer)
RETURNS bigint
LANGUAGE plpgsql
VOLATILE
-- the text of a value tgsis.same_row_sql compares is one text per value under these
-- (floats shortest-exact, date and time ISO with offsets), whatever the session's
SET DateStyle = 'ISO, YMD'
SET IntervalStyle = 'postgres'
SET extra_float_digits = 1
SET bytea_output = 'hex'
SET lc_monetary = 'C'
AS $$
DECLARE
    v_t       tgsis.versioned_tables;
    v_ver     text;
    v_cols    text;
    v_keytype text;
    v_count   bigint;
    v_written bigint := 0;
    v_chunks  bigint := 0;  -- of v_written: chunk versions (tables stored in chunks)
    v_chunked boolean;
    v_same    text;
    v_changed text;  -- (v.revision in the symmetric difference, or v closed in one of its revisions)
    -- visible only in p_to, only in p_from (rows f of the storage): the rows copy_object_state acts on
    v_to_only   CONSTANT text := 'f.revision = ANY ($3) AND NOT (f.lastrevs && $3)
                                  AND NOT (f.revision = ANY ($2) AND NOT (f.lastrevs && $2))';
    v_from_only CONSTANT text := 'f.revision = ANY ($2) AND NOT (f.lastrevs && $2)
                                  AND NOT (f.revision = ANY ($3) AND NOT (f.lastrevs && $3))';
BEGIN
    IF cardinality(p_keys) = 0 THEN
        RETURN 0;
    END IF;
    v_changed := format('(v.revision = ANY (%1$L::integer[]) OR (v.revclosed AND v.lastrevs && %1$L::integer[]))',
                        ARRAY(SELECT r FROM ((SELECT unnest(p_from) EXCEPT SELECT unnest(p_to))
                                             UNION (SELECT unnest(p_to) EXCEPT SELECT unnest(p_from))) AS d(r)
                               WHERE r IS NOT NULL ORDER BY r));
    -- closes first (reverse iudorder), then copies (iudorder): closing touches
    -- only rows p_from does not see, so it cannot change what is copied, and
    -- copies made first would look like rows to close
    FOR v_t IN SELECT * FROM tgsis.versioned_tables WHERE objectclass = p_objectclass ORDER BY iudorder DESC, shortname LOOP
        v_ver := tgsis.storage_table(v_t.schemaname, v_t.tablename);  -- <table>_ver, or tgsis.<table>_chunk
        v_chunked := v_ver <> format('%I.%I', v_t.schemaname, v_t.tablename || '_ver');
        v_keytype := tgsis.object_key_type(v_t);  -- keys compared in the column's own type, so that its index serves
        -- a row v only p_to sees stays when its key's one row only p_from sees holds its content
        v_same := tgsis.copy_object_match_sql(v_t, v_to_only, v_from_only);
        -- (every statement on storage as its owner: tgsis.storage_run)
        SELECT r[1]::bigint INTO v_count FROM tgsis.storage_run(v_t, true, format(
            'DELETE FROM %s v WHERE v.%I = ANY ($1::%s[]) AND v.revision = $4 AND %s
                AND v.revision = ANY ($3) AND NOT (v.lastrevs && $3)
                AND NOT (v.revision = ANY ($2) AND NOT (v.lastrevs && $2))
                AND NOT %s',
            v_ver, v_t.objectkeyfield, v_keytype, v_changed, v_same),
            p_keys, p_from, p_to, p_revision) AS r;
        v_written := v_written + v_count;
        v_chunks := v_chunks + CASE WHEN v_chunked THEN v_count ELSE 0 END;
        -- other versions see these rows too (the siblings of a merged version share
        -- the parent's rows): closed without waiting for one while holding others
        v_count := tgsis.update_shared_rows(v_t, 'lastrevs = v.lastrevs || $4', format(
            'v.%I = ANY ($1::%s[]) AND v.revision <> $4 AND %s
                AND v.revision = ANY ($3) AND NOT (v.lastrevs && $3)
                AND NOT (v.revision = ANY ($2) AND NOT (v.lastrevs && $2))
                AND NOT %s',
            v_t.objectkeyfield, v_keytype, v_changed, v_same), p_keys, p_from, p_to, p_revision);
        v_written := v_written + v_count;
        v_chunks := v_chunks + CASE WHEN v_chunked THEN v_count ELSE 0 END;
        IF v_count > 0 THEN
            -- closed in p_revision: noted for the next merge or conflict check (tgsis.revision_objects)
            PERFORM tgsis.note_changed_objects(v_t.schemaname, v_t.tablename, p_revision, p_keys);
        END IF;
    END LOOP;
    FOR v_t IN SELECT * FROM tgsis.versioned_tables WHERE objectclass = p_objectclass ORDER BY iudorder, shortname LOOP
        v_ver := tgsis.storage_table(v_t.schemaname, v_t.tablename);  -- <table>_ver, or tgsis.<table>_chunk
        v_chunked := v_ver <> format('%I.%I', v_t.schemaname, v_t.tablename || '_ver');
        -- every stored column but the generated ones; a fresh revision, nothing closed
        SELECT string_agg(format('%I', attname), ', ' ORDER BY attnum) INTO v_cols
          FROM pg_catalog.pg_attribute
         WHERE attrelid = v_ver::regclass AND attnum > 0 AND NOT attisdropped AND attgenerated = ''
           AND attname NOT IN ('revision', 'lastrevs');
        v_keytype := tgsis.object_key_type(v_t);
        -- a row v only p_from sees is not copied when its key's one row only p_to sees holds
        -- its content and was left open by the closes above (those closed in p_revision are gone)
        v_same := tgsis.copy_object_match_sql(v_t, v_from_only, v_to_only || ' AND NOT ($4 = ANY (f.lastrevs))');
        SELECT r[1]::bigint INTO v_count FROM tgsis.storage_run(v_t, true, format(
            'INSERT INTO %s (%s, revision)
             SELECT %s, $4 FROM %s v
              WHERE v.%I = ANY ($1::%s[]) AND %s
                AND v.revision = ANY ($2) AND NOT (v.lastrevs && $2)
                AND NOT (v.revision = ANY ($3) AND NOT (v.lastrevs && $3))
                AND NOT %s',
            v_ver, v_cols, v_cols, v_ver, v_t.objectkeyfield, v_keytype, v_changed, v_same),
            p_keys, p_from, p_to, p_revision) AS r;
        v_written := v_written + v_count;
        v_chunks := v_chunks + CASE WHEN v_chunked THEN v_count ELSE 0 END;
        IF v_count > 0 THEN
            -- (the storage's statement trigger notes them too, unless this runs inside a trigger)
            PERFORM tgsis.note_changed_objects(v_t.schemaname, v_t.tablename, p_revision, p_keys);
        END IF;
    END LOOP;
    IF v_chunks > 0 THEN
        PERFORM set_config('tgsis.chunk_versions_written',
                           (CASE WHEN current_setting('tgsis.chunk_versions_written', true) ~ '^[0-9]{1,18}$'
                                 THEN current_setting('tgsis.chunk_versions_written', true)::bigint ELSE 0 END
                            + v_chunks)::text, true);
    END IF;
    RETURN v_written;
END
$$;

COMMENT ON FUNCTION tgsis.copy_object_state(text, text[], integer[], integer[], integer) IS
    'make objects of a class look in revision set p_to (plus p_revision) as they look in p_from: close or delete rows only p_to sees, copy rows only p_from sees, except a row key''s one row only p_to sees when the one only p_from sees holds exactly its content (then both are left alone); returns rows written (rows and chunk versions; the chunk versions also added to the transaction''s setting tgsis.chunk_versions_written)';
