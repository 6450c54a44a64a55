-- tgsis.storage_rows_check(): AFTER INSERT statement trigger on every <table>_ver: rows written directly belong to the session's working revision.
-- A role writing storage directly (the client's COPY upload) may only add
-- live rows labelled with the working revision of a version where it holds
-- the write right, and only to objects no other version has locked. The rows
-- are read from the statement's transition table, once per statement (a
-- row trigger would double the upload); a wrong one fails the statement,
-- naming how many rows and which revision they had to carry.
-- Rows of features of classes without versioning (tgsis.unversioned_features)
-- carry revision 0 instead, and only in DEFAULT's working revision.
-- Trigger arguments: object class, object key column, and the table's name
-- when its storage is not named <table>_ver (tgsis.<table>_chunk).
CREATE FUNCTION tgsis.storage_rows_check()
RETURNS trigger
LANGUAGE plpgsql
VOLATILE
SECURITY DEFINER
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_write record;
    v_bad   bigint;
    v_first text;
    v_keys  text[];
    v_none  bigint[];
BEGIN
    SELECT * INTO v_write FROM tgsis.write_revision();  -- TG002, TG301
    -- features of classes without versioning: their rows carry revision 0 (tgsis.unversioned_revision says when)
    IF TG_ARGV[0] = 'feature' AND EXISTS (SELECT FROM tgsis.unversioned_features) THEN
        -- (the distinct keys of the statement against the registry, not a probe per row)
        EXECUTE format('SELECT array_agg(u.geoid) FROM tgsis.unversioned_features u '
                       'WHERE u.geoid IN (SELECT n.%I FROM tgsis_new_rows n)', TG_ARGV[1])
           INTO v_none;
    END IF;
    IF v_none IS NOT NULL THEN
        PERFORM tgsis.unversioned_revision(v_none);  -- TG305 outside DEFAULT's working revision
        EXECUTE format('SELECT count(*), min(n.revision::text) FROM tgsis_new_rows n '
                       'WHERE n.revision IS DISTINCT FROM CASE WHEN n.%I = ANY ($2) THEN 0 ELSE $1 END '
                       'OR n.lastrevs IS DISTINCT FROM ''{}''::integer[]', TG_ARGV[1])
           INTO v_bad, v_first USING v_write.revision, v_none;
    ELSE
        SELECT count(*), min(n.revision::text) INTO v_bad, v_first
          FROM tgsis_new_rows n
         WHERE n.revision IS DISTINCT FROM v_write.revision OR n.lastrevs IS DISTINCT FROM '{}'::integer[];
    END IF;
    IF v_bad > 0 THEN
        RAISE EXCEPTION '% row(s) written into %.% are not live rows of revision %, the working revision of version %',
                v_bad, TG_TABLE_SCHEMA, TG_TABLE_NAME, v_write.revision, quote_literal(tgsis.get_working_version())
            USING ERRCODE = 'TG002',
                  DETAIL = format('Rows written directly into storage must have revision = %s and lastrevs = ''{}'' (one had revision %s)%s.',
                                  v_write.revision, coalesce(v_first, 'NULL'),
                                  CASE WHEN v_none IS NOT NULL THEN format('; rows of features of classes without versioning '
                                       '(geoids %s) revision = 0', array_to_string(v_none[1:5], ', ')
                                       || CASE WHEN cardinality(v_none) > 5 THEN ', ...' ELSE '' END) ELSE '' END),
                  HINT = format('write through the view %I.%I, or label the rows with SELECT revision FROM tgsis.write_revision()',
                                TG_TABLE_SCHEMA, coalesce(TG_ARGV[2], left(TG_TABLE_NAME, -4)));
    END IF;
    IF EXISTS (SELECT FROM tgsis.object_locks l WHERE l.objectclass = TG_ARGV[0]) THEN
        PERFORM tgsis.check_key_type(TG_RELID, TG_ARGV[1]);
        -- the keys' canonical text (tgsis.object_key_sql), as the locks hold them
        EXECUTE format('SELECT array_agg(DISTINCT %s) FROM tgsis_new_rows n',
                       tgsis.object_key_sql((SELECT a.atttypid FROM pg_catalog.pg_attribute a
                                              WHERE a.attrelid = TG_RELID AND a.attname = TG_ARGV[1]),
                                            format('n.%I', TG_ARGV[1]))) INTO v_keys;
        PERFORM tgsis.check_objects_unlocked(TG_ARGV[0], v_keys, v_write.versionid);
    END IF;
    RETURN NULL;
END
$$;

COMMENT ON FUNCTION tgsis.storage_rows_check() IS
    'AFTER INSERT statement trigger of <table>_ver storage (transition table tgsis_new_rows): rows a role other than the owners writes directly must be live rows of its working revision, in a version where it holds the write right, of objects no other version locked';
