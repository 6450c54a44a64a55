-- tgsis.copy_object_state(objectclass, keys, from_set, to_set, revision): make objects look in to_set as they look in from_set.
-- For every table of the class, the rows of the objects visible in to_set but
-- not in from_set are closed with revision (deleted when written in it), and
-- the rows visible in from_set but not in to_set are copied with revision.
-- Rows visible in both are left alone: unchanged rows are never copied.
-- The common step of merge (child's state into the parent) and refresh.
-- The objects are noted as changed in revision (tgsis.revision_objects).
-- Returns the rows written (closed, deleted and copied).
CREATE FUNCTION tgsis.copy_object_state(
    p_objectclass text,
    p_keys        text[],
    p_from        integer[],
    p_to          integer[],
    p_revision    integer)
RETURNS bigint
LANGUAGE plpgsql
VOLATILE
AS $$
DECLARE
    v_t       tgsis.versioned_tables;
    v_ver     text;
    v_cols    text;
    v_keytype text;
    v_count   bigint;
    v_written bigint := 0;
BEGIN
    IF cardinality(p_keys) = 0 THEN
        RETURN 0;
    END IF;
    -- closes first (reverse iudorder), then copies (iudorder): closing touches
    -- only rows p_from does not see, so it cannot change what is copied, and
    -- copies made first would look like rows to close
    FOR v_t IN SELECT * FROM tgsis.versioned_tables WHERE objectclass = p_objectclass ORDER BY iudorder DESC, shortname LOOP
        v_ver := format('%I.%I', v_t.schemaname, v_t.tablename || '_ver');
        v_keytype := tgsis.object_key_type(v_t);  -- keys compared in the column's own type, so that its index serves
        -- (every statement on storage as its owner: tgsis.storage_run)
        SELECT r[1]::bigint INTO v_count FROM tgsis.storage_run(v_t, true, format(
            'DELETE FROM %s v WHERE v.%I = ANY ($1::%s[]) AND v.revision = $4
                AND v.revision = ANY ($3) AND NOT (v.lastrevs && $3)
                AND NOT (v.revision = ANY ($2) AND NOT (v.lastrevs && $2))',
            v_ver, v_t.objectkeyfield, v_keytype), p_keys, p_from, p_to, p_revision) AS r;
        v_written := v_written + v_count;
        -- other versions see these rows too (the siblings of a merged version share
        -- the parent's rows): closed without waiting for one while holding others
        v_count := tgsis.update_shared_rows(v_t, 'lastrevs = v.lastrevs || $4', format(
            'v.%I = ANY ($1::%s[]) AND v.revision <> $4
                AND v.revision = ANY ($3) AND NOT (v.lastrevs && $3)
                AND NOT (v.revision = ANY ($2) AND NOT (v.lastrevs && $2))',
            v_t.objectkeyfield, v_keytype), p_keys, p_from, p_to, p_revision);
        v_written := v_written + v_count;
        IF v_count > 0 THEN
            -- closed in p_revision: noted for the next merge or conflict check (tgsis.revision_objects)
            PERFORM tgsis.note_changed_objects(v_t.schemaname, v_t.tablename, p_revision, p_keys);
        END IF;
    END LOOP;
    FOR v_t IN SELECT * FROM tgsis.versioned_tables WHERE objectclass = p_objectclass ORDER BY iudorder, shortname LOOP
        v_ver := format('%I.%I', v_t.schemaname, v_t.tablename || '_ver');
        -- every stored column but the generated ones; a fresh revision, nothing closed
        SELECT string_agg(format('%I', attname), ', ' ORDER BY attnum) INTO v_cols
          FROM pg_catalog.pg_attribute
         WHERE attrelid = v_ver::regclass AND attnum > 0 AND NOT attisdropped AND attgenerated = ''
           AND attname NOT IN ('revision', 'lastrevs');
        v_keytype := tgsis.object_key_type(v_t);
        SELECT r[1]::bigint INTO v_count FROM tgsis.storage_run(v_t, true, format(
            'INSERT INTO %s (%s, revision)
             SELECT %s, $4 FROM %s v
              WHERE v.%I = ANY ($1::%s[])
                AND v.revision = ANY ($2) AND NOT (v.lastrevs && $2)
                AND NOT (v.revision = ANY ($3) AND NOT (v.lastrevs && $3))',
            v_ver, v_cols, v_cols, v_ver, v_t.objectkeyfield, v_keytype), p_keys, p_from, p_to, p_revision) AS r;
        v_written := v_written + v_count;
        IF v_count > 0 THEN
            -- (the storage's statement trigger notes them too, unless this runs inside a trigger)
            PERFORM tgsis.note_changed_objects(v_t.schemaname, v_t.tablename, p_revision, p_keys);
        END IF;
    END LOOP;
    RETURN v_written;
END
$$;

COMMENT ON FUNCTION tgsis.copy_object_state(text, text[], integer[], integer[], integer) IS
    'make objects of a class look in revision set p_to (plus p_revision) as they look in p_from: close or delete rows only p_to sees, copy rows only p_from sees; returns rows written';
