-- tgsis.versioning_trigger_source(schema, table, key columns, columns, pkey name, object class, object key column): the
-- CREATE FUNCTION statement of the INSTEAD OF trigger that routes writes on
-- the view <table> into <table>_ver. Generated per table with static SQL so
-- that PL/pgSQL caches the plans (dynamic SQL would be planned per row).
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
IMMUTABLE
AS $gen$
DECLARE
    v_ver      text := format('%I.%I', p_schema, p_table || '_ver');
    v_cols     text;
    v_new      text;
    v_assign   text;
    v_old_key  text;
    v_new_key  text;
    v_key_vals text;
    v_key_list text;
    v_visible  CONSTANT text := 'v.revision = ANY (v_set) AND NOT (v.lastrevs && v_set)';
    v_dup      text;
BEGIN
    SELECT string_agg(format('%I', c), ', ' ORDER BY o),
           string_agg(format('NEW.%I', c), ', ' ORDER BY o),
           string_agg(format('%I = NEW.%I', c, c), ', ' ORDER BY o)
      INTO v_cols, v_new, v_assign
      FROM unnest(p_columns) WITH ORDINALITY AS u(c, o);
    SELECT string_agg(format('v.%I = OLD.%I', k, k), ' AND ' ORDER BY o),
           string_agg(format('v.%I = NEW.%I', k, k), ' AND ' ORDER BY o),
           string_agg(format('NEW.%I::text', k), ', ' ORDER BY o),
           string_agg(format('%I', k), ', ' ORDER BY o)
      INTO v_old_key, v_new_key, v_key_vals, v_key_list
      FROM unnest(p_keys) WITH ORDINALITY AS u(k, o);
    -- the error a plain table would raise, so applications that catch 23505 keep working
    v_dup := format($dup$
            RAISE EXCEPTION 'duplicate key value violates unique constraint %%', %L
                USING ERRCODE = 'unique_violation',
                      DETAIL = format(%L, concat_ws(', ', %s), tgsis.get_working_version()),
                      CONSTRAINT = %L, TABLE = %L, SCHEMA = %L;$dup$,
        '"' || p_pkey || '"',
        'Key (' || replace(v_key_list, '%', '%%') || ')=(%s) already exists in version %s.',
        v_key_vals, p_pkey, p_table, p_schema);

    RETURN format($fn$
CREATE FUNCTION %1$I.%2$I()
RETURNS trigger
LANGUAGE plpgsql
SECURITY DEFINER
SET search_path = pg_catalog, pg_temp
AS $body$
-- Written by tgsis.enable_versioning: writes on the view %1$s.%3$s go to %4$s
-- as row versions labelled with the session's working revision.
DECLARE
    v_w    integer;
    v_set  integer[];
    v_keys text[];
BEGIN
    -- the write right was checked once for the statement (tgsis.view_write_check)
    SELECT w.revision, w.revisions INTO v_w, v_set FROM tgsis.write_revision(false) AS w;
    -- object locks: one index probe per row; the check names the holders
    IF TG_OP = 'INSERT' THEN
        v_keys := ARRAY[NEW.%15$I::text];
    ELSIF TG_OP = 'DELETE' THEN
        v_keys := ARRAY[OLD.%15$I::text];
    ELSE
        v_keys := ARRAY[OLD.%15$I::text, NEW.%15$I::text];
    END IF;
    IF EXISTS (SELECT FROM tgsis.object_locks l WHERE l.objectclass = %14$L AND l.objectkey = ANY (v_keys)) THEN
        PERFORM tgsis.check_objects_unlocked(%14$L, v_keys);
    END IF;
    IF TG_OP = 'INSERT' THEN
        IF EXISTS (SELECT FROM %4$s v WHERE %6$s AND %9$s) THEN%10$s
        END IF;
        INSERT INTO %4$s (%5$s, revision) VALUES (%7$s, v_w);
        RETURN NEW;
    ELSIF TG_OP = 'UPDATE' THEN
        -- a new key is a delete of the old key and an insert of the new one
        IF ROW(%11$s) IS DISTINCT FROM ROW(%12$s)
           AND EXISTS (SELECT FROM %4$s v WHERE %6$s AND %9$s) THEN%10$s
        END IF;
        UPDATE %4$s v SET %8$s WHERE %13$s AND v.revision = v_w;
        IF NOT FOUND THEN
            UPDATE %4$s v SET lastrevs = v.lastrevs || v_w WHERE %13$s AND %9$s;
            INSERT INTO %4$s (%5$s, revision) VALUES (%7$s, v_w);
        END IF;
        RETURN NEW;
    END IF;
    DELETE FROM %4$s v WHERE %13$s AND v.revision = v_w;
    IF NOT FOUND THEN
        UPDATE %4$s v SET lastrevs = v.lastrevs || v_w WHERE %13$s AND %9$s;
    END IF;
    RETURN OLD;
END
$body$$fn$,
        p_schema, p_table || '_ver_write', p_table, v_ver, v_cols, v_new_key, v_new, v_assign, v_visible, v_dup,
        (SELECT string_agg(format('NEW.%I', k), ', ' ORDER BY o) FROM unnest(p_keys) WITH ORDINALITY AS u(k, o)),
        (SELECT string_agg(format('OLD.%I', k), ', ' ORDER BY o) FROM unnest(p_keys) WITH ORDINALITY AS u(k, o)),
        v_old_key, p_class, p_keyfield);
END
$gen$;

COMMENT ON FUNCTION tgsis.versioning_trigger_source(text, text, text[], text[], text, text, text) IS
    'source of the INSTEAD OF INSERT/UPDATE/DELETE trigger function <table>_ver_write() that enable_versioning creates';
