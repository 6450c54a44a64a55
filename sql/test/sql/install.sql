-- make installcheck: CREATE EXTENSION tgsis gives a whole installation.
-- (pg_regress compares this file's output with ../expected/install.out)
\set VERBOSITY terse
SET client_min_messages = warning;
CREATE EXTENSION tgsis CASCADE;
-- the storage tables are created after CREATE EXTENSION, so that pg_dump keeps them (tgsis.install does this)
SELECT tgsis.create_storage() AS created;
SELECT tgsis.create_storage() AS created_again;

SELECT tgsis.version() = extversion AS version_matches FROM pg_extension WHERE extname = 'tgsis';
SELECT method FROM tgsis.installation;
SELECT rolname FROM pg_roles WHERE rolname IN ('tgsis_reader', 'tgsis_editor', 'tgsis_admin', 'tgsis_nobody') ORDER BY 1;

-- every data model has its tables, hooks and rights
SELECT model, name, timemodel FROM tgsis.data_models ORDER BY model;
SELECT tablename FROM tgsis.model_tables WHERE to_regclass(format('tgsis.%I', tablename)) IS NULL;
SELECT model FROM tgsis.data_models
 WHERE model > 0 AND (to_regprocedure(format('tgsis.%I(bigint)', extent_function)) IS NULL
                      OR to_regprocedure(format('tgsis.%I(bigint)', check_function)) IS NULL);
SELECT tablename FROM tgsis.model_tables
 WHERE NOT has_table_privilege('tgsis_reader', format('tgsis.%I', tablename), 'SELECT')
    OR NOT has_table_privilege('tgsis_editor', format('tgsis.%I', tablename), 'INSERT');

-- every function and table says what it is
-- (the constructors PostgreSQL makes for a range type are its own)
SELECT p.oid::regprocedure FROM pg_proc p
 WHERE p.pronamespace = 'tgsis'::regnamespace AND obj_description(p.oid, 'pg_proc') IS NULL
   AND NOT EXISTS (SELECT FROM pg_depend d WHERE d.classid = 'pg_proc'::regclass AND d.objid = p.oid AND d.deptype = 'i');
SELECT c.relname FROM pg_class c
 WHERE c.relnamespace = 'tgsis'::regnamespace AND c.relkind IN ('r', 'v') AND obj_description(c.oid, 'pg_class') IS NULL;

-- definer code pins its search path (docs/security.md)
SELECT p.oid::regprocedure FROM pg_proc p
 WHERE p.pronamespace = 'tgsis'::regnamespace AND p.prosecdef
   AND NOT EXISTS (SELECT FROM unnest(p.proconfig) c WHERE c LIKE 'search\_path=%');

-- the storage tables are not extension members (pg_dump dumps them)
SELECT c.relname FROM pg_depend d JOIN pg_class c ON c.oid = d.objid
 WHERE d.deptype = 'e' AND d.refobjid = (SELECT oid FROM pg_extension WHERE extname = 'tgsis')
   AND c.relname IN (SELECT tablename FROM tgsis.model_tables);
