-- tgsis.enable_versioning_rel(table, objectkeyfield, objectclass, iudorder, shortname): version a table in place.
-- Called by tgsis.enable_versioning, which resolves the table name in the
-- caller's search_path; this one runs with a fixed search_path so that the
-- constraint definitions it records are schema-qualified.
-- The table's storage becomes <table>_ver (its columns plus revision and
-- lastrevs, primary key extended by revision) and a view <table> with the
-- original columns, defaults, comments and grants takes its place, so that
-- plain SELECT/INSERT/UPDATE/DELETE keep working, in the session's version.
-- Constraints that cannot hold across versions (foreign keys between
-- versioned tables, other unique keys) are dropped and recorded so that
-- disable_versioning can restore them.
CREATE FUNCTION tgsis.enable_versioning_rel(
    p_table          regclass,
    p_objectkeyfield text,
    p_objectclass    text,
    p_iudorder       integer DEFAULT 0,
    p_shortname      text    DEFAULT NULL)
RETURNS tgsis.versioned_tables
LANGUAGE plpgsql
VOLATILE
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_rel       regclass := p_table;
    v_schema    text;
    v_table     text;
    v_kind      "char";
    v_owner     oid;
    v_ver       text;
    v_pkey      text;
    v_keys      text[];
    v_columns   text[];
    v_dependent text;
    v_identity  text[];
    v_skip      text;
    v_relacl    aclitem[];
    v_name      text;
    v_comment   text := obj_description(p_table, 'pg_class');
    v_con       record;
    v_acl       record;
BEGIN
    SELECT n.nspname, c.relname, c.relkind, c.relowner INTO v_schema, v_table, v_kind, v_owner
      FROM pg_class c JOIN pg_namespace n ON n.oid = c.relnamespace WHERE c.oid = v_rel;
    IF EXISTS (SELECT FROM tgsis.versioned_tables WHERE schemaname = v_schema AND tablename = v_table) THEN
        RAISE EXCEPTION 'table %.% is versioned already', v_schema, v_table USING ERRCODE = 'TG201';
    END IF;
    IF v_kind NOT IN ('r', 'p') THEN
        RAISE EXCEPTION '%.% is not a table: only ordinary and partitioned tables can be versioned', v_schema, v_table
            USING ERRCODE = 'TG100',
                  DETAIL = format('Its kind is %s.', CASE v_kind WHEN 'v' THEN 'a view' WHEN 'm' THEN 'a materialized view'
                                                              WHEN 'f' THEN 'a foreign table' ELSE v_kind::text END);
    END IF;
    -- a partitioned table: the storage's statement triggers (rights, labels, notes of changed objects) are
    -- the parent's and do not run for rows written into a partition by its name, so nobody but the owner
    -- may reach a partition (its rights are its own, not the parent's)
    IF v_kind = 'p' THEN
        SELECT string_agg(DISTINCT format('%s (%s)', p.relid::regclass,
                                          CASE WHEN a.grantee = 0 THEN 'PUBLIC' ELSE pg_get_userbyid(a.grantee) END), ', ')
          INTO v_dependent
          FROM pg_partition_tree(v_rel) p JOIN pg_class c ON c.oid = p.relid,
               LATERAL aclexplode(c.relacl) a
         WHERE p.relid <> v_rel AND a.grantee <> c.relowner;
        IF v_dependent IS NOT NULL THEN
            RAISE EXCEPTION 'partitions of %.% grant rights to other roles: %', v_schema, v_table, v_dependent
                USING ERRCODE = 'TG100',
                      DETAIL = 'Rows written into a partition by its name skip the checks versioning attaches to the table.',
                      HINT = 'revoke them (REVOKE ALL ON <partition> FROM <role>); grant on the table instead, versioning keeps those';
        END IF;
    END IF;
    -- in tgsis's schema only the registered storage of the data models
    IF v_schema = 'tgsis' AND NOT EXISTS (SELECT FROM tgsis.model_tables WHERE tablename = v_table) THEN
        RAISE EXCEPTION 'tgsis.% is part of tgsis''s own catalog and cannot be versioned', v_table USING ERRCODE = 'TG100';
    END IF;
    IF NOT pg_has_role(current_user, v_owner, 'USAGE') THEN
        RAISE EXCEPTION 'only the owner of %.% (%) may version it', v_schema, v_table, pg_get_userbyid(v_owner)
            USING ERRCODE = 'TG002';
    END IF;
    -- (its registration goes through definer helpers that only tgsis_admin may call)
    IF NOT pg_has_role(tgsis.calling_role(), 'tgsis_admin', 'MEMBER') THEN
        RAISE EXCEPTION 'role % may not version tables', tgsis.calling_role()
            USING ERRCODE = 'TG002', DETAIL = 'Versioning tables is for members of tgsis_admin that own them.',
                  HINT = format('a DBA may run: GRANT tgsis_admin TO %I', tgsis.calling_role());
    END IF;
    v_ver := v_table || '_ver';
    IF octet_length(v_table || '_ver_write') > 63 THEN
        RAISE EXCEPTION 'table name % is too long to be versioned', quote_literal(v_table)
            USING ERRCODE = 'TG101',
                  DETAIL = 'Versioning adds <table>_ver, <table>_ver_queue and <table>_ver_write(), which must fit in 63 bytes.';
    END IF;
    IF to_regclass(format('%I.%I', v_schema, v_ver)) IS NOT NULL
       OR to_regclass(format('%I.%I', v_schema, v_table || '_ver_queue')) IS NOT NULL
       OR to_regprocedure(format('%I.%I()', v_schema, v_table || '_ver_write')) IS NOT NULL
       OR EXISTS (SELECT FROM pg_proc WHERE pronamespace = to_regnamespace(quote_ident(v_schema))
                                        AND proname = v_table || '_ver_run') THEN
        RAISE EXCEPTION '%.%, %.%, %.%() or %.%() exists already', v_schema, v_ver, v_schema, v_table || '_ver_queue',
                v_schema, v_table || '_ver_write', v_schema, v_table || '_ver_run'
            USING ERRCODE = 'TG201',
                  HINT = 'versioning needs these names for the table''s storage, write queue, trigger and runner';
    END IF;
    IF p_objectclass IS NULL OR btrim(p_objectclass) = '' OR p_iudorder IS NULL THEN
        RAISE EXCEPTION 'versioning %.% needs an object class and an iudorder', v_schema, v_table USING ERRCODE = 'TG100';
    END IF;
    IF EXISTS (SELECT FROM tgsis.versioned_tables
                WHERE objectclass = p_objectclass AND shortname = coalesce(p_shortname, v_table)) THEN
        RAISE EXCEPTION 'object class % has a table with short name % already', quote_literal(p_objectclass),
                quote_literal(coalesce(p_shortname, v_table))
            USING ERRCODE = 'TG201', HINT = 'pass another p_shortname';
    END IF;

    SELECT con.conname, array_agg(a.attname::text ORDER BY k.ord) INTO v_pkey, v_keys
      FROM pg_constraint con
      CROSS JOIN LATERAL unnest(con.conkey) WITH ORDINALITY AS k(attnum, ord)
      JOIN pg_attribute a ON a.attrelid = con.conrelid AND a.attnum = k.attnum
     WHERE con.conrelid = v_rel AND con.contype = 'p'
     GROUP BY con.conname;
    IF v_pkey IS NULL THEN
        RAISE EXCEPTION 'table %.% has no primary key', v_schema, v_table
            USING ERRCODE = 'TG100', HINT = 'versioning tells the rows of a table apart by its primary key: add one first';
    END IF;
    SELECT array_agg(attname::text ORDER BY attnum) INTO v_columns
      FROM pg_attribute WHERE attrelid = v_rel AND attnum > 0 AND NOT attisdropped;
    IF v_columns && ARRAY['revision', 'lastrevs', 'revclosed'] THEN
        RAISE EXCEPTION 'table %.% has a column named revision, lastrevs or revclosed, which versioning needs', v_schema, v_table
            USING ERRCODE = 'TG100', HINT = 'rename the column first';
    END IF;
    IF p_objectkeyfield IS NULL OR NOT p_objectkeyfield = ANY (v_columns) THEN
        RAISE EXCEPTION 'table %.% has no column % to hold the object key', v_schema, v_table,
                coalesce(quote_literal(p_objectkeyfield), 'NULL')
            USING ERRCODE = 'TG200', DETAIL = format('Its columns: %s.', array_to_string(v_columns, ', '));
    END IF;
    -- keys are cast to and from text by tgsis's definer code: with a type of
    -- its own (a domain's check, a cast) the table's owner would run code there
    IF (SELECT atttypid FROM pg_attribute WHERE attrelid = v_rel AND attname = p_objectkeyfield) >= 16384 THEN
        RAISE EXCEPTION 'the object key column % of %.% is of type %, which is not built into PostgreSQL', p_objectkeyfield,
                v_schema, v_table, (SELECT format_type(atttypid, atttypmod) FROM pg_attribute
                                     WHERE attrelid = v_rel AND attname = p_objectkeyfield)
            USING ERRCODE = 'TG100',
                  DETAIL = 'tgsis''s own functions read and compare object keys as tgsis''s owner; a type of one''s own could run its owner''s code there.',
                  HINT = 'key the objects by a column of a built-in type (integer, bigint, text, uuid, ...)';
    END IF;
    -- ... and compared as text, one text per key in every session (types without one refused, named)
    PERFORM tgsis.check_key_canonical(v_rel, p_objectkeyfield);

    -- views and rules reading the table would read every row version afterwards
    SELECT string_agg(DISTINCT r.ev_class::regclass::text, ', ') INTO v_dependent
      FROM pg_depend d JOIN pg_rewrite r ON d.classid = 'pg_rewrite'::regclass AND d.objid = r.oid
     WHERE d.refclassid = 'pg_class'::regclass AND d.refobjid = v_rel AND r.ev_class <> v_rel;
    IF v_dependent IS NOT NULL THEN
        RAISE EXCEPTION 'views depend on %.%: %', v_schema, v_table, v_dependent
            USING ERRCODE = 'TG202', HINT = 'drop them, enable versioning, then create them again: they will read the versioned view';
    END IF;
    -- foreign keys into the table from plain tables cannot follow it
    SELECT string_agg(format('%s (%s)', con.conrelid::regclass, con.conname), ', ') INTO v_dependent
      FROM pg_constraint con
     WHERE con.confrelid = v_rel AND con.contype = 'f' AND con.conrelid <> v_rel
       AND NOT EXISTS (SELECT FROM tgsis.versioned_tables t JOIN pg_class c ON c.relname = t.tablename || '_ver'
                         JOIN pg_namespace n ON n.oid = c.relnamespace AND n.nspname = t.schemaname
                        WHERE c.oid = con.conrelid);
    IF v_dependent IS NOT NULL THEN
        RAISE EXCEPTION 'foreign keys of plain tables refer to %.%: %', v_schema, v_table, v_dependent
            USING ERRCODE = 'TG202', HINT = 'version those tables too (their keys are then dropped), or drop the constraints';
    END IF;

    -- what cannot hold across versions: foreign keys to versioned tables (and
    -- from them into this one), self references, unique keys other than the
    -- primary key, exclusion constraints
    FOR v_con IN
        SELECT con.oid, con.conname, con.conrelid, con.confrelid
          FROM pg_constraint con
         WHERE (con.conrelid = v_rel AND con.contype IN ('u', 'x'))
            OR (con.contype = 'f' AND (con.confrelid = v_rel OR (con.conrelid = v_rel AND (
                    con.confrelid = v_rel OR EXISTS (
                        SELECT FROM tgsis.versioned_tables t JOIN pg_class c ON c.relname = t.tablename || '_ver'
                          JOIN pg_namespace n ON n.oid = c.relnamespace AND n.nspname = t.schemaname
                         WHERE c.oid = con.confrelid)))))
         ORDER BY con.contype, con.conname
    LOOP
        -- a key of another versioned table into this one: only that table's owner may drop it
        IF NOT pg_has_role(current_user, (SELECT relowner FROM pg_class WHERE oid = v_con.conrelid), 'USAGE') THEN
            RAISE EXCEPTION 'foreign key % of % refers to %.%, and role % may not drop it', v_con.conname,
                    v_con.conrelid::regclass, v_schema, v_table, current_user
                USING ERRCODE = 'TG002',
                      DETAIL = 'Keys between versioned tables cannot hold across versions; versioning drops them.',
                      HINT = format('the owner of %s may drop the key, or make that table plain and drop it there', v_con.conrelid::regclass);
        END IF;
        PERFORM tgsis.record_dropped(v_rel, v_con.oid);  -- its definition, read from the catalogs
        EXECUTE format('ALTER TABLE %s DROP CONSTRAINT %I', v_con.conrelid::regclass, v_con.conname);
    END LOOP;
    FOR v_con IN
        SELECT c.relname::text AS idx, i.indexrelid
          FROM pg_index i JOIN pg_class c ON c.oid = i.indexrelid
         WHERE i.indrelid = v_rel AND i.indisunique
           AND NOT EXISTS (SELECT FROM pg_constraint con WHERE con.conindid = i.indexrelid)
    LOOP
        PERFORM tgsis.record_dropped(v_rel, v_con.indexrelid, true);
        EXECUTE format('DROP INDEX %I.%I', v_schema, v_con.idx);
    END LOOP;
    SELECT coalesce(array_agg(attname::text ORDER BY attnum), '{}') INTO v_identity
      FROM pg_attribute WHERE attrelid = v_rel AND attnum > 0 AND NOT attisdropped AND attidentity = 'a';

    -- storage
    EXECUTE format('ALTER TABLE %I.%I RENAME TO %I', v_schema, v_table, v_ver);
    FOREACH v_name IN ARRAY v_identity LOOP
        EXECUTE format('ALTER TABLE %I.%I ALTER COLUMN %I SET GENERATED BY DEFAULT', v_schema, v_ver, v_name);
    END LOOP;
    EXECUTE format('ALTER TABLE %I.%I ADD COLUMN revision integer NOT NULL DEFAULT 0, '
                   'ADD COLUMN lastrevs integer[] NOT NULL DEFAULT ''{}'', '
                   -- a plain flag the view tests before lastrevs: reading an array
                   -- copies it out of the row, and almost every row is live
                   'ADD COLUMN revclosed boolean GENERATED ALWAYS AS (cardinality(lastrevs) > 0) STORED', v_schema, v_ver);
    -- existing rows are revision 0: DEFAULT's first revision, in every version's set
    EXECUTE format('ALTER TABLE %I.%I ALTER COLUMN revision DROP DEFAULT', v_schema, v_ver);
    EXECUTE format('ALTER TABLE %I.%I DROP CONSTRAINT %I', v_schema, v_ver, v_pkey);
    EXECUTE format('ALTER TABLE %I.%I ADD CONSTRAINT %I PRIMARY KEY (%s, revision)', v_schema, v_ver, v_ver || '_pkey',
                   (SELECT string_agg(format('%I', k), ', ' ORDER BY o) FROM unnest(v_keys) WITH ORDINALITY AS u(k, o)));
    IF v_keys[1] <> p_objectkeyfield THEN
        EXECUTE format('CREATE INDEX %I ON %I.%I (%I, revision)', v_ver || '_object_idx', v_schema, v_ver, p_objectkeyfield);
    END IF;
    -- the rows written or closed in given revisions, found by index (merges, refreshes, merges by region)
    PERFORM tgsis.create_revision_indexes(v_schema, v_table, p_objectkeyfield);
    -- statistics for the rewritten table (the new columns have none; a fresh table none at all): the view's
    -- reads are planned from them at once, not after autovacuum's first pass (ewkb_geometry measured 57 s -> 0.19 s)
    EXECUTE format('ANALYZE %I.%I', v_schema, v_ver);  -- (the caller owns it: checked above)
    EXECUTE format('COMMENT ON TABLE %I.%I IS %L', v_schema, v_ver,
                   format('row versions of %s.%s (tgsis versioning): read and write it through the view %s.%s',
                          v_schema, v_table, v_schema, v_table));
    EXECUTE format('COMMENT ON COLUMN %I.%I.revision IS %L', v_schema, v_ver, 'revision in which this row version was written');
    EXECUTE format('COMMENT ON COLUMN %I.%I.revclosed IS %L', v_schema, v_ver,
                   'lastrevs is not empty (kept by PostgreSQL): lets reads skip the array for live rows');
    EXECUTE format('COMMENT ON COLUMN %I.%I.lastrevs IS %L', v_schema, v_ver,
                   'revisions in which this row version stopped being current (updated or deleted there); empty while live');

    -- storage keeps the table's SELECT and INSERT grants, for the client's bulk path (COPY upload); rows are
    -- changed and closed only through the view and tgsis's functions, so no other role may update or delete
    -- them (disable_versioning gives the grants back from the view's)
    SELECT relacl INTO v_relacl FROM pg_class WHERE oid = v_rel;  -- the view gets them all, below
    FOR v_acl IN
        SELECT DISTINCT a.grantee FROM aclexplode(v_relacl) AS a
         WHERE a.grantee <> v_owner
           AND a.privilege_type IN ('UPDATE', 'DELETE', 'TRUNCATE', 'REFERENCES', 'TRIGGER')
    LOOP
        EXECUTE format('REVOKE UPDATE, DELETE, TRUNCATE, REFERENCES, TRIGGER ON %I.%I FROM %s', v_schema, v_ver,
                       CASE WHEN v_acl.grantee = 0 THEN 'PUBLIC' ELSE quote_ident(pg_get_userbyid(v_acl.grantee)) END);
    END LOOP;
    -- direct writers need the version's write right and may only add live rows of its working revision
    -- (not the table's owner, as whom the view's row trigger writes, nor tgsis's, as whom merges write:
    -- the WHEN spares them a call per statement)
    -- (by role name, not oid: a dump restored into another cluster keeps the names, not the oids)
    v_skip := format('NOT pg_catalog.pg_has_role(current_user, %L::name, ''USAGE'') '
                     'AND NOT pg_catalog.pg_has_role(current_user, %L::name, ''USAGE'')',
                     pg_get_userbyid(v_owner), (SELECT pg_get_userbyid(nspowner) FROM pg_namespace WHERE nspname = 'tgsis'));
    EXECUTE format('CREATE TRIGGER tgsis_storage_write BEFORE INSERT OR UPDATE OR DELETE OR TRUNCATE ON %I.%I '
                   'FOR EACH STATEMENT WHEN (%s) EXECUTE FUNCTION tgsis.storage_write_check()', v_schema, v_ver, v_skip);
    EXECUTE format('CREATE TRIGGER tgsis_storage_rows AFTER INSERT ON %I.%I REFERENCING NEW TABLE AS tgsis_new_rows '
                   'FOR EACH STATEMENT WHEN (%s) EXECUTE FUNCTION tgsis.storage_rows_check(%L, %L)',
                   v_schema, v_ver, v_skip, p_objectclass, p_objectkeyfield);
    -- and every direct insert notes the objects it wrote (tgsis.revision_objects), the owners' too
    PERFORM tgsis.create_change_trigger(v_schema, v_table, p_objectkeyfield);

    -- the view in the table's place, with its defaults, comments, grants and owner
    PERFORM tgsis.create_versioned_view(v_schema, v_table, v_keys, v_pkey, p_objectclass, p_objectkeyfield, v_relacl,
                                        coalesce(v_comment || ' ', '')
                                        || format('(versioned by tgsis: rows of the session''s version; storage %s)', v_ver));
    -- through which tgsis's definer code acts on the storage, as its owner
    PERFORM tgsis.create_storage_runner(v_schema, v_table);

    -- recorded by tgsis's definer helper, which checks what it records against the catalogs
    RETURN tgsis.register_versioned_table(format('%I.%I', v_schema, v_table)::regclass, p_objectkeyfield, p_objectclass,
                                          p_iudorder, p_shortname, v_pkey, v_comment, v_identity);
END
$$;

COMMENT ON FUNCTION tgsis.enable_versioning_rel(regclass, text, text, integer, text) IS
    'the work of tgsis.enable_versioning on a resolved table: version a table: storage renamed <table>_ver (+ revision, lastrevs, revclosed), a view <table> with INSTEAD OF triggers takes its place; registered in tgsis.versioned_tables';
