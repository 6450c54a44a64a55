-- tgsis 0.2.0 -> 0.3.0: the hand-written part of the upgrade script.
-- 0.2.0 is frozen (sql/upgrade/tgsis--0.2.0.sql, the install script of commit e012a4a). The build
-- (src/tgsis/db/_upgrade.py) puts the functions, views and comments of 0.3.0 at the @sources line,
-- after dropping those whose shape changed; this file does what re-running them cannot: changed
-- tables, new catalog tables and their rows, triggers, what the storage needs
-- (docs/developing.md, "An upgrade script"). tests/test_upgrade.py checks that a database of every
-- released version upgraded by it equals a fresh 0.3.0.
--
-- Layout: each change is one block starting with a line `-- ---- <what>`; blocks that must run before
-- the functions come before `-- @sources`, those that need the new functions go into the DO block
-- after it (one per change, marked the same way) or after it. The installation record comes last.

-- ---- tgsis.catalog: classes without versioning (issue 18)
ALTER TABLE tgsis.catalog ADD COLUMN versioned boolean NOT NULL DEFAULT true;
-- @handled core/catalog.sql

-- ---- tgsis.installation: the fingerprint of the install script each row's version was built from
ALTER TABLE tgsis.installation ADD COLUMN fingerprint text;
COMMENT ON COLUMN tgsis.installation.fingerprint IS
    'sha256 (first 16 hex digits) of the install script of that version as built (tgsis.install and tgsis db status compare it with the client''s); NULL for versions before 0.3.0';
-- @handled core/installation.sql

-- ---- core/roles.sql: its DO block runs at install only (creating missing roles); its hint changed
-- @handled core/roles.sql
-- ---- versioning/storage_hop.sql: its DO block (the owner's membership of tgsis_nobody) runs at install only
-- @handled versioning/storage_hop.sql

-- ---- new catalog tables, dumped with the catalog: the features of classes registered without
-- versioning, and the notes of which objects changed in which revision (filled from the storage after
-- the functions, below)
-- @include versioning/unversioned_features.sql
-- @include versioning/revision_objects.sql
DO $dump$
BEGIN
    IF EXISTS (SELECT FROM pg_catalog.pg_extension WHERE extname = 'tgsis') THEN
        PERFORM pg_catalog.pg_extension_config_dump('tgsis.unversioned_features'::regclass, '');
        PERFORM pg_catalog.pg_extension_config_dump('tgsis.revision_objects'::regclass, '');
    END IF;
END
$dump$;
-- @handled core/config_dump.sql

-- ---- the rows tgsis ships: error codes and property types added since flow in from the files
-- @rows core/error_codes.sql
-- @rows core/property_types.sql

-- ---- (blocks of later changes that must run before the functions go here: -- ---- issue36-NAME: ...)

-- ---- issue39-review1: the read policy of tgsis.conflict_regions (in versioning/conflict_regions.sql) names
-- tgsis.class_denied_geoids, new in 0.3.0: made before the table (made again, the same, at @sources)
-- @include geometry/class_denied_geoids.sql

-- ---- issue39-store: the regions of conflicting meshes (tgsis.conflict_regions), a new catalog table
-- dumped with the conflicts (final/config_dump.sql)
-- @include versioning/conflict_regions.sql
DO $dump$
BEGIN
    IF EXISTS (SELECT FROM pg_catalog.pg_extension WHERE extname = 'tgsis') THEN
        PERFORM pg_catalog.pg_extension_config_dump('tgsis.conflict_regions'::regclass, '');
    END IF;
END
$dump$;
-- @handled final/config_dump.sql

-- ---- issue38-sql-layers: the SQL folders became layers (sources.txt, one block per folder); these
-- files of 0.2.0 moved without a change to their tables or rows (nothing to run; the directives above
-- may name them by either name)
-- @moved versioning/calling_role.sql core/calling_role.sql
-- @moved temporal/checked_time.sql core/checked_time.sql
-- @moved geometry/data_models.sql core/data_models.sql
-- @moved core/property_types.sql catalog/property_types.sql
-- @moved core/catalog.sql catalog/catalog.sql
-- @moved core/class_tables.sql catalog/class_tables.sql
-- @moved core/catalog_row.sql catalog/catalog_row.sql
-- @moved core/property_columns.sql catalog/property_columns.sql
-- @moved core/comment_property_columns.sql catalog/comment_property_columns.sql
-- @moved core/time_key_columns.sql catalog/time_key_columns.sql
-- @moved core/comment_time_key_columns.sql catalog/comment_time_key_columns.sql
-- @moved core/create_class_view.sql geometry/create_class_view.sql
-- @moved temporal/temporal_geometry.sql geometry/temporal_geometry.sql
-- @moved core/create_storage.sql storage/create_storage.sql
-- @moved core/storage.sql storage/storage.sql
-- @moved model4/check_gmap_geometry.sql temporal/check_gmap_geometry.sql
-- @moved geometry/new_geometry.sql features/new_geometry.sql
-- @moved geometry/geometries_in_box.sql features/geometries_in_box.sql
-- @moved geometry/delete_stored_geometries.sql features/delete_stored_geometries.sql
-- @moved geometry/delete_geometry.sql features/delete_geometry.sql
-- @moved core/register_feature_class.sql classes/register_feature_class.sql
-- @moved core/drop_feature_class.sql classes/drop_feature_class.sql
-- @moved core/restore_shipped_row.sql final/restore_shipped_row.sql
-- @moved core/config_dump.sql final/config_dump.sql
-- @moved core/grants.sql final/grants.sql

-- ---- issue39-B: the registry names the function that merges a feature of a model slice by slice in SQL
-- (tgsis.merge_regions_in_sql calls it): models 2 and 3 ship one
ALTER TABLE tgsis.data_models ADD COLUMN merge_function text;
UPDATE tgsis.data_models SET merge_function = 'merge_instants_by_slice' WHERE model = 2;
UPDATE tgsis.data_models SET merge_function = 'merge_periods_by_slice' WHERE model = 3;
-- @handled core/data_models.sql
-- @handled model2/storage.sql
-- @handled model3/storage.sql

-- ---- issue40-chunks: the registry says which model tables are stored in chunks (core/data_models.sql;
-- tgsis.create_chunk_table reads it): model 1's vertices and simplices, by their local id, 1024 per chunk
ALTER TABLE tgsis.model_tables
    ADD COLUMN chunkcolumn text,
    ADD COLUMN chunkrefs   text[] NOT NULL DEFAULT '{}',
    ADD COLUMN chunksize   integer,
    ADD CONSTRAINT model_tables_chunks CHECK ((chunkcolumn IS NULL) = (chunksize IS NULL)
                                              AND (chunkcolumn IS NOT NULL OR chunkrefs = '{}')
                                              AND (chunksize IS NULL OR (chunksize >= 64 AND chunksize <= 16384
                                                                         AND chunksize & (chunksize - 1) = 0))),
    -- model 1's tables are stored in chunks by default, model 2's and 3's per-vertex/cell tables are registered for them only
    ADD COLUMN chunkdefault boolean NOT NULL DEFAULT false,
    ADD CONSTRAINT model_tables_chunkdefault CHECK (NOT chunkdefault OR chunkcolumn IS NOT NULL);
COMMENT ON COLUMN tgsis.model_tables.chunkdefault IS
    'stored in chunks by default in a new database: switched by tgsis.create_storage unless tgsis.storage is rows (model 1''s tables, model 2''s time tables); the upgrade from 0.2.0 switches model 1''s only, an upgraded database keeps its time tables as rows; a table registered for chunks without it stays rows until tgsis.store_in_chunks (model 3''s, the G-maps'')';
UPDATE tgsis.model_tables t SET chunkcolumn = c.chunkcolumn, chunkrefs = c.chunkrefs, chunksize = 1024, chunkdefault = c.dflt
  FROM (VALUES ('vrtx', 'vrtxid', '{}'::text[], true), ('point', 'pointid', '{vrtxid1}', true),
               ('segment', 'segid', '{vrtxid1,vrtxid2}', true), ('trgl', 'trglid', '{vrtxid1,vrtxid2,vrtxid3}', true),
               ('tetra', 'tetraid', '{vrtxid1,vrtxid2,vrtxid3,vrtxid4}', true),
               ('times_vrtx', 'vrtxid', '{}', true), ('times_trgl', 'trglid', '{vrtxid1,vrtxid2,vrtxid3}', true),
               ('d4dtrgl', 'trglid', '{nodeid1,nodeid2,nodeid3}', false), ('d4dvrtx', 'nodeid', '{}', false),
               ('gmap_dart', 'dartid', '{nodeid}', false), ('gmap_alpha', 'dartid', '{dartid2}', false),
               ('md_dart', 'dartid', '{vrtxid}', false), ('md_alpha', 'dartid', '{dartid2}', false),
               ('gmap_vertex', 'nodeid', '{}', false), ('md_vertex', 'vrtxid', '{}', false))
       AS c (tablename, chunkcolumn, chunkrefs, dflt)
 WHERE t.tablename = c.tablename;
-- @handled model1/storage.sql
-- (the G-map darts, involutions and points, models 4 and 5: registered for chunks, stored as rows until switched)
-- @handled model4/storage.sql
-- @handled model5/storage.sql

-- ---- issue40-chunk-layout: the chunk layout of a table cannot change under its chunk table (a trigger on
-- tgsis.model_tables; chunks/chunk_layout_guard.sql says why): made whole here, before the generated
-- part comments on the trigger
-- @include chunks/chunk_layout_guard.sql

-- ---- issue36-timerange: tgsis.timerange becomes a domain refusing NaN bounds over the range type
-- tgsis.modeltime_range (temporal/timerange.sql says why). No table stores one. The functions over the
-- old range type are dropped by name (the generated part below makes them again), then the type, without
-- CASCADE: a user's view or function built on them stops the upgrade with PostgreSQL's error naming it,
-- rather than being dropped without a word.
DROP FUNCTION tgsis.invalid_period(text, double precision, double precision);
DROP FUNCTION tgsis.linear_satisfied(double precision, double precision, double precision, double precision, text, double precision);
DROP FUNCTION tgsis.instant_periods(bigint, text);
DROP FUNCTION tgsis.evolving_satisfied(double precision, double precision, double precision, double precision, double precision, double precision, boolean, text, double precision);
DROP FUNCTION tgsis.property_periods(text, bigint, text, text, double precision, text);
DROP FUNCTION tgsis.class_property_periods(text, text, text, double precision, text);
DROP TYPE tgsis.timerange;
-- @include temporal/timerange.sql

-- @sources

-- ---- after the functions: what versioned tables need (the storage tables are no extension members:
-- core/create_storage.sql says why)
DO $upgrade$
DECLARE
    v_extension oid;   -- NULL on the plain-SQL route
    v_members   text[];
    v_object    record;
    v_t         tgsis.versioned_tables;
BEGIN
    v_extension := (SELECT oid FROM pg_catalog.pg_extension WHERE extname = 'tgsis');
    v_members := ARRAY(SELECT d.classid::oid::text || ':' || d.objid::text FROM pg_catalog.pg_depend d
                        WHERE d.deptype = 'e' AND d.refobjid = v_extension);

    -- ---- revision notes, features of no version, set-based view updates
    -- every versioned table:
    -- * the write triggers of the views, generated anew: they note the objects they change
    --   (tgsis.revision_objects), and those of object class 'feature' tell rows of features of no
    --   version (tgsis.unversioned_features) from versioned ones;
    -- * the statement's queue of rows and its flush trigger (tgsis.create_versioning_queue);
    -- * the storage's trigger that notes direct inserts;
    -- * the notes of what its rows say changed in each revision (revision 0 is never noted)
    FOR v_t IN SELECT * FROM tgsis.versioned_tables t ORDER BY t.schemaname, t.tablename LOOP
        CONTINUE WHEN EXISTS (SELECT FROM pg_catalog.pg_trigger g
                               WHERE g.tgname = 'tgsis_storage_changes'
                                 AND g.tgrelid = format('%I.%I', v_t.schemaname, v_t.tablename || '_ver')::regclass);
        EXECUTE format('DROP FUNCTION %I.%I() CASCADE', v_t.schemaname, v_t.tablename || '_ver_write');  -- and its trigger
        PERFORM tgsis.create_versioning_trigger(v_t.schemaname, v_t.tablename, v_t.keycolumns, v_t.pkeyname,
                                                v_t.objectclass, v_t.objectkeyfield);
        PERFORM tgsis.create_change_trigger(v_t.schemaname, v_t.tablename, v_t.objectkeyfield);
        -- (read as the storage's owner, like all of tgsis's reads of storage: tgsis.storage_run)
        PERFORM tgsis.check_key_type(format('%I.%I', v_t.schemaname, v_t.tablename || '_ver')::regclass, v_t.objectkeyfield);
        INSERT INTO tgsis.revision_objects (revision, schemaname, tablename, objectkey)
        SELECT r[1]::integer, v_t.schemaname, v_t.tablename, r[2]
          FROM tgsis.storage_run(v_t, false, format(
                   'SELECT ARRAY[c.r::text, c.k::text]
                      FROM (SELECT v.revision, v.%1$I FROM %2$I.%3$I v
                            UNION
                            SELECT l.r, v.%1$I FROM %2$I.%3$I v, unnest(v.lastrevs) AS l(r) WHERE v.revclosed) AS c(r, k)
                     WHERE c.r <> 0', v_t.objectkeyfield, v_t.schemaname, v_t.tablename || '_ver')) AS r;
    END LOOP;

    -- ---- (blocks of later changes that need the new functions go here)

    -- ---- issue40-nan-boxes: the GiST indexes over boxes leave out the keys with a NaN (partial indexes; their keys
    -- spoiled the inner boxes and an index scan missed valid rows a sequential scan found: tgsis.cube_has_nan,
    -- model5/storage.sql say why): tgsis.geometry's bbox, model 5's extents and points. Each made again on the
    -- relation that holds it (the table, or its _ver storage when versioned; a partitioned parent's partitions
    -- follow), with its name; nothing where the storage has none.
    FOR v_object IN
        SELECT i.indexrelid::regclass AS idx, i.indrelid::regclass AS rel, c.relname AS name, d.pred
          FROM (VALUES ('geometry_bbox_idx', 'gist (bbox) WHERE NOT tgsis.cube_has_nan(bbox)'),
                       ('md_gmap_extent_idx', 'gist (extent) WHERE NOT tgsis.cube_has_nan(extent)'),
                       ('md_vertex_point_idx', 'gist (cube(coordinate)) WHERE NOT ''NaN''::double precision = ANY (coordinate)'))
               AS d (name, pred)
          JOIN pg_catalog.pg_class c ON c.relname = d.name AND c.relnamespace = 'tgsis'::regnamespace
          JOIN pg_catalog.pg_index i ON i.indexrelid = c.oid
         WHERE i.indpred IS NULL
    LOOP
        EXECUTE format('DROP INDEX %s', v_object.idx);
        EXECUTE format('CREATE INDEX %I ON %s USING %s', v_object.name, v_object.rel, v_object.pred);
    END LOOP;

    -- ---- issue39-speed: the indexes that find a versioned table's row versions by revision
    -- (tgsis.create_revision_indexes: a BRIN on revision, a btree on the object key of closed rows;
    -- on the cell tables of models 1, 2 and 3 the BRIN on geoid, instant or period and vertex columns,
    -- tgsis.times_trgl's and tgsis.d4dtrgl's since issue39-D), which a fresh tgsis.enable_versioning_rel makes
    FOR v_t IN SELECT * FROM tgsis.versioned_tables t ORDER BY t.schemaname, t.tablename LOOP
        PERFORM tgsis.create_revision_indexes(v_t.schemaname, v_t.tablename, v_t.objectkeyfield);
    END LOOP;

    -- ---- issue36-rls: per-class rights at the model tables (docs/security.md)
    -- the storage's row-level security keyed by the classes' rights (a fresh install's create_storage does it);
    -- the versioned views of the model tables filter by them as security barriers (tgsis.create_versioned_view);
    -- their write triggers, generated anew where they lack the class check (tgsis.check_class_write)
    PERFORM tgsis.protect_model_tables(m.model) FROM tgsis.data_models m ORDER BY m.model;
    FOR v_t IN SELECT v.* FROM tgsis.versioned_tables v JOIN tgsis.model_tables t ON v.schemaname = 'tgsis' AND t.tablename = v.tablename
                WHERE t.geoidcolumn IS NOT NULL ORDER BY v.tablename LOOP
        CONTINUE WHEN EXISTS (SELECT FROM pg_catalog.pg_proc p
                               WHERE p.oid = to_regprocedure(format('tgsis.%I()', v_t.tablename || '_ver_write'))
                                 AND p.prosrc LIKE '%check_class_write%');
        EXECUTE format('DROP FUNCTION tgsis.%I() CASCADE', v_t.tablename || '_ver_write');  -- and its triggers
        PERFORM tgsis.create_versioning_trigger(v_t.schemaname, v_t.tablename, v_t.keycolumns, v_t.pkeyname,
                                                v_t.objectclass, v_t.objectkeyfield);
    END LOOP;
    FOR v_object IN
        SELECT t.tablename, t.geoidcolumn,
               ARRAY(SELECT a.attname::text FROM pg_catalog.pg_attribute a
                      WHERE a.attrelid = format('tgsis.%I', t.tablename || '_ver')::regclass AND a.attnum > 0
                        AND NOT a.attisdropped AND a.attname NOT IN ('revision', 'lastrevs', 'revclosed')
                      ORDER BY a.attnum) AS columns
          FROM tgsis.model_tables t JOIN tgsis.versioned_tables v ON v.schemaname = 'tgsis' AND v.tablename = t.tablename
         WHERE t.geoidcolumn IS NOT NULL ORDER BY t.tablename
    LOOP
        -- (the views of tables versioned just now filter already)
        CONTINUE WHEN pg_catalog.pg_get_viewdef(format('tgsis.%I', v_object.tablename)::regclass) LIKE '%class_denied_geoids%';
        IF v_extension IS NOT NULL THEN  -- an extension replaces only its members: one for now (it leaves below)
            EXECUTE format('ALTER EXTENSION tgsis ADD VIEW tgsis.%I', v_object.tablename);
        END IF;
        EXECUTE regexp_replace(tgsis.versioned_view_source('tgsis', v_object.tablename, v_object.columns),
                               '^CREATE VIEW', 'CREATE OR REPLACE VIEW')
                || ' AND ' || tgsis.class_rights_filter(v_object.geoidcolumn, 'SELECT', 'v');
        EXECUTE format('ALTER VIEW tgsis.%I SET (security_barrier = true)', v_object.tablename);
    END LOOP;

    -- What this block made (storage tables, their versioned views and runners, class views made
    -- again) is made at run time in a fresh install: inside ALTER EXTENSION it became an extension
    -- member, which pg_dump leaves out and DROP EXTENSION drops. It leaves the extension again.
    FOR v_object IN
        SELECT o.type, o.identity
          FROM pg_catalog.pg_depend d, LATERAL pg_catalog.pg_identify_object(d.classid, d.objid, d.objsubid) o
         WHERE d.deptype = 'e' AND d.refobjid = v_extension
           AND (d.classid::oid::text || ':' || d.objid::text) <> ALL (v_members)
         ORDER BY CASE WHEN o.type IN ('table', 'view', 'sequence') THEN 0 WHEN o.type = 'type' THEN 1 ELSE 2 END,
                  o.identity LIKE '%[]'
    LOOP
        -- a relation takes its row type along on recent servers: skip what went with an earlier one
        IF EXISTS (SELECT FROM pg_catalog.pg_depend d, LATERAL pg_catalog.pg_identify_object(d.classid, d.objid, d.objsubid) o
                    WHERE d.deptype = 'e' AND d.refobjid = v_extension AND o.type = v_object.type AND o.identity = v_object.identity) THEN
            EXECUTE format('ALTER EXTENSION tgsis DROP %s %s', v_object.type, v_object.identity);
        END IF;
    END LOOP;
END
$upgrade$;

-- ---- (blocks of later changes that run after the functions, outside the DO block, go here)

-- ---- issue36-keys: object keys stored as text under other sessions' settings, made canonical
-- Tables keyed by a type whose text depends on the session (date, timestamp(tz), float, numeric,
-- interval, bytea: tgsis.object_key_kind) get their write triggers generated anew (they name
-- objects by tgsis.object_key_text now), and the keys their notes, locks and conflicts hold are read
-- back in the key's type with this session's settings and written as canonical text: ISO text
-- (what the default DateStyle wrote) reads the same under any setting; text another DateStyle wrote
-- is read as this session's DateStyle reads it (a warning says how many keys were rewritten). A lock
-- or conflict whose canonical key is held already (the same object under two texts) goes.
DO $keys$
DECLARE
    v_extension oid := (SELECT oid FROM pg_catalog.pg_extension WHERE extname = 'tgsis');
    v_members   text[];
    v_object    record;
    v_t         tgsis.versioned_tables;
    v_type      oid;
    v_old       record;
    v_new       text;
    v_changed   bigint;
BEGIN
    v_members := ARRAY(SELECT d.classid::oid::text || ':' || d.objid::text FROM pg_catalog.pg_depend d
                        WHERE d.deptype = 'e' AND d.refobjid = v_extension);
    FOR v_t IN SELECT * FROM tgsis.versioned_tables t ORDER BY t.schemaname, t.tablename LOOP
        v_type := (SELECT a.atttypid FROM pg_catalog.pg_attribute a
                    WHERE a.attrelid = format('%I.%I', v_t.schemaname, v_t.tablename || '_ver')::regclass
                      AND a.attname = v_t.objectkeyfield AND NOT a.attisdropped);
        -- keys of a type enable_versioning refuses from now on: named as before, and said so
        IF tgsis.object_key_kind(v_type) IS NULL THEN
            RAISE WARNING 'the object key column % of %.% is of type %, which has no text independent of the session''s settings',
                    quote_ident(v_t.objectkeyfield), quote_ident(v_t.schemaname), quote_ident(v_t.tablename), format_type(v_type, NULL)
                USING DETAIL = 'Its objects are named by the type''s text as before; enable_versioning refuses such keys now.',
                      HINT = 'disable its versioning and key it by a column of a scalar type (docs/versioning.md, "Object keys")';
            CONTINUE;
        END IF;
        IF EXISTS (SELECT FROM pg_catalog.pg_attribute a JOIN pg_catalog.pg_collation c ON c.oid = a.attcollation
                    WHERE a.attrelid = format('%I.%I', v_t.schemaname, v_t.tablename || '_ver')::regclass
                      AND a.attname = v_t.objectkeyfield AND NOT c.collisdeterministic) THEN
            RAISE WARNING 'the object key column % of %.% has a nondeterministic collation', quote_ident(v_t.objectkeyfield),
                    quote_ident(v_t.schemaname), quote_ident(v_t.tablename)
                USING DETAIL = 'Keys its equality holds equal are named by different texts; enable_versioning refuses such keys now.',
                      HINT = 'disable its versioning and give the column a deterministic collation (docs/versioning.md, "Object keys")';
        END IF;
        CONTINUE WHEN tgsis.object_key_kind(v_type) = 'cast';   -- text of no setting: nothing to rewrite
        EXECUTE format('DROP FUNCTION %I.%I() CASCADE', v_t.schemaname, v_t.tablename || '_ver_write');  -- and its triggers
        EXECUTE format('DROP TABLE IF EXISTS %I.%I', v_t.schemaname, v_t.tablename || '_ver_queue');
        PERFORM tgsis.create_versioning_trigger(v_t.schemaname, v_t.tablename, v_t.keycolumns, v_t.pkeyname,
                                                v_t.objectclass, v_t.objectkeyfield);
        v_changed := 0;
        FOR v_old IN
            SELECT 'revision_objects' AS tbl, o.objectkey AS k, NULL::integer AS versionid FROM tgsis.revision_objects o
             WHERE o.schemaname = v_t.schemaname AND o.tablename = v_t.tablename
            UNION SELECT 'object_locks', l.objectkey, l.versionid FROM tgsis.object_locks l WHERE l.objectclass = v_t.objectclass
            UNION SELECT 'conflicts', c.objectkey, c.versionid FROM tgsis.conflicts c WHERE c.objectclass = v_t.objectclass
        LOOP
            BEGIN
                EXECUTE format('SELECT %s FROM (SELECT $1::%s AS k) AS s', tgsis.object_key_sql(v_type, 's.k'), v_type::regtype)
                   INTO v_new USING v_old.k;
            EXCEPTION WHEN data_exception THEN
                RAISE WARNING 'key % of %.% in tgsis.% is no %: left as it is', quote_literal(v_old.k), v_t.schemaname,
                        v_t.tablename, v_old.tbl, format_type(v_type, NULL);
                CONTINUE;
            END;
            CONTINUE WHEN v_new = v_old.k;
            v_changed := v_changed + 1;
            IF v_old.tbl = 'revision_objects' THEN
                UPDATE tgsis.revision_objects SET objectkey = v_new
                 WHERE schemaname = v_t.schemaname AND tablename = v_t.tablename AND objectkey = v_old.k;
            ELSIF v_old.tbl = 'object_locks' THEN
                IF EXISTS (SELECT FROM tgsis.object_locks WHERE objectclass = v_t.objectclass AND objectkey = v_new) THEN
                    DELETE FROM tgsis.object_locks WHERE objectclass = v_t.objectclass AND objectkey = v_old.k;
                ELSE
                    UPDATE tgsis.object_locks SET objectkey = v_new WHERE objectclass = v_t.objectclass AND objectkey = v_old.k;
                END IF;
            ELSIF EXISTS (SELECT FROM tgsis.conflicts WHERE versionid = v_old.versionid AND objectclass = v_t.objectclass
                                                        AND objectkey = v_new) THEN
                DELETE FROM tgsis.conflicts WHERE versionid = v_old.versionid AND objectclass = v_t.objectclass AND objectkey = v_old.k;
            ELSE
                UPDATE tgsis.conflicts SET objectkey = v_new
                 WHERE versionid = v_old.versionid AND objectclass = v_t.objectclass AND objectkey = v_old.k;
            END IF;
        END LOOP;
        IF v_changed > 0 THEN
            RAISE WARNING '% object keys of %.% rewritten as canonical text (read with DateStyle %, TimeZone %)', v_changed,
                    v_t.schemaname, v_t.tablename, current_setting('DateStyle'), current_setting('TimeZone');
        END IF;
    END LOOP;
    -- the write triggers and queues made here are made at run time in a fresh install: not extension members
    FOR v_object IN
        SELECT o.type, o.identity
          FROM pg_catalog.pg_depend d, LATERAL pg_catalog.pg_identify_object(d.classid, d.objid, d.objsubid) o
         WHERE d.deptype = 'e' AND d.refobjid = v_extension
           AND (d.classid::oid::text || ':' || d.objid::text) <> ALL (v_members)
         ORDER BY CASE WHEN o.type IN ('table', 'view', 'sequence') THEN 0 WHEN o.type = 'type' THEN 1 ELSE 2 END,
                  o.identity LIKE '%[]'
    LOOP
        IF EXISTS (SELECT FROM pg_catalog.pg_depend d, LATERAL pg_catalog.pg_identify_object(d.classid, d.objid, d.objsubid) o
                    WHERE d.deptype = 'e' AND d.refobjid = v_extension AND o.type = v_object.type AND o.identity = v_object.identity) THEN
            EXECUTE format('ALTER EXTENSION tgsis DROP %s %s', v_object.type, v_object.identity);
        END IF;
    END LOOP;
END
$keys$;

-- ---- issue40-md-nan: model 5's extents (tgsis.md_gmap.extent) and 3D boxes (tgsis.geometry.bbox) are of the
-- points without a NaN coordinate, as tgsis.md_vertices_in_box finds none of those. 0.2.0's tgsis.md_extent
-- counted a NaN as the largest value: a G-map whose points an SQL edit gave a NaN, measured then by
-- tgsis.refresh_geometry, holds a box with a NaN (the client refuses NaN points: there is no other way in),
-- which tgsis.md_in_box answers by the plan. Those boxes are measured again here. Where tgsis.md_gmap is
-- versioned, each version and revision holds its own: none is rewritten, a WARNING names them (the
-- refresh in each version is the owner's: tgsis.check_geometry reports them stale meanwhile).
DO $md_nan$
DECLARE
    v_geoid  bigint;
    v_geoids bigint[];
BEGIN
    IF to_regclass('tgsis.md_gmap') IS NULL THEN
        RETURN;
    END IF;
    v_geoids := ARRAY(SELECT m.geoid FROM tgsis.md_gmap m JOIN tgsis.geometry g ON g.geoid = m.geoid
                       WHERE m.extent::text LIKE '%NaN%' OR g.bbox::text LIKE '%NaN%' ORDER BY m.geoid);
    IF cardinality(v_geoids) = 0 THEN
        RETURN;
    END IF;
    IF EXISTS (SELECT FROM tgsis.versioned_tables t WHERE t.schemaname = 'tgsis' AND t.tablename IN ('md_gmap', 'geometry')) THEN
        RAISE WARNING 'the extents of % multiply indexed G-maps hold a NaN, as measured before 0.3.0', cardinality(v_geoids)
            USING DETAIL = format('geoids %s; they are versioned and were left as they are.', array_to_string(v_geoids[1:20], ', ')),
                  HINT = 'in each version holding them: SELECT tgsis.refresh_geometry(geoid) (tgsis.check_geometry reports them stale)';
        RETURN;
    END IF;
    FOREACH v_geoid IN ARRAY v_geoids LOOP
        PERFORM tgsis.refresh_geometry(v_geoid);
    END LOOP;
END
$md_nan$;

-- ---- issue40-default: model 1 is stored in chunks (docs/storage.md, "The storage switch"): its tables,
-- with their data, versioned or not, switched by tgsis.store_in_chunks, which verifies that every version
-- and revision sees the same rows before the row storage goes. After the blocks above (they read the
-- <table>_ver of versioned tables). The setting tgsis.storage = rows keeps rows (tgsis.chosen_storage:
-- `tgsis db install --storage rows`, or SET in psql first). A table that cannot switch stays rows with a
-- WARNING naming it and the way to switch later: partitioned storage (TG100), or a layout chunks do not
-- hold (TG100), or a user's view over it (PostgreSQL's 2BP01); the upgrade goes on. What the switch makes
-- is made at run time in a fresh install (tgsis.create_storage): not extension members.
-- Model 2's time tables (times_vrtx, times_trgl) are chunkdefault too (a new database stores them in
-- chunks), but an upgraded database keeps its existing time tables where they are, as rows: only model 1's
-- tables are switched here (tgsis.store_in_chunks('times_vrtx') etc. moves them later, docs/storage.md).
DO $chunks$
DECLARE
    v_extension oid := (SELECT oid FROM pg_catalog.pg_extension WHERE extname = 'tgsis');
    v_members   text[];
    v_object    record;
    v_table     text;
    v_message   text;
    v_detail    text;
BEGIN
    IF tgsis.chosen_storage() <> 'chunks' THEN  -- (TG001 for a bad value: the upgrade stops, naming it)
        RETURN;
    END IF;
    v_members := ARRAY(SELECT d.classid::oid::text || ':' || d.objid::text FROM pg_catalog.pg_depend d
                        WHERE d.deptype = 'e' AND d.refobjid = v_extension);
    FOR v_table IN SELECT t.tablename FROM tgsis.model_tables t
                    WHERE t.chunkdefault AND t.model = 1  -- model 2's time tables (chunkdefault) stay rows here
                      AND to_regclass(format('tgsis.%I', t.tablename)) IS NOT NULL
                    ORDER BY t.model, t.iudorder, t.tablename LOOP
        CONTINUE WHEN tgsis.stored_in_chunks(v_table);
        BEGIN
            PERFORM tgsis.store_in_chunks(v_table);
        EXCEPTION WHEN SQLSTATE 'TG100' OR dependent_objects_still_exist THEN
            GET STACKED DIAGNOSTICS v_message = MESSAGE_TEXT, v_detail = PG_EXCEPTION_DETAIL;
            RAISE WARNING 'tgsis.% stays stored as rows: %', quote_ident(v_table), v_message
                USING DETAIL = concat_ws(' ', nullif(v_detail, ''),
                                         'The upgrade stores model 1 in chunks (docs/storage.md); this table could not be switched, nothing of it changed.'),
                      HINT = format('in psql, as tgsis''s owner, once the cause is gone (a view of yours dropped, the partitioning undone): SELECT tgsis.store_in_chunks(%L)', v_table);
        END;
    END LOOP;
    FOR v_object IN
        SELECT o.type, o.identity
          FROM pg_catalog.pg_depend d, LATERAL pg_catalog.pg_identify_object(d.classid, d.objid, d.objsubid) o
         WHERE d.deptype = 'e' AND d.refobjid = v_extension
           AND (d.classid::oid::text || ':' || d.objid::text) <> ALL (v_members)
         ORDER BY CASE WHEN o.type IN ('table', 'view', 'sequence') THEN 0 WHEN o.type = 'type' THEN 1 ELSE 2 END,
                  o.identity LIKE '%[]'
    LOOP
        IF EXISTS (SELECT FROM pg_catalog.pg_depend d, LATERAL pg_catalog.pg_identify_object(d.classid, d.objid, d.objsubid) o
                    WHERE d.deptype = 'e' AND d.refobjid = v_extension AND o.type = v_object.type AND o.identity = v_object.identity) THEN
            EXECUTE format('ALTER EXTENSION tgsis DROP %s %s', v_object.type, v_object.identity);
        END IF;
    END LOOP;
END
$chunks$;

-- ---- the installation record (last)
INSERT INTO tgsis.installation (version, method, fingerprint)
VALUES ('@TGSIS_VERSION@',
        CASE WHEN EXISTS (SELECT FROM pg_catalog.pg_extension WHERE extname = 'tgsis')
             THEN 'extension' ELSE 'sql' END,
        '@TGSIS_FINGERPRINT@');
