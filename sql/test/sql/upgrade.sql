-- make installcheck: ALTER EXTENSION tgsis UPDATE from the last release, 0.2.0 (frozen in sql/upgrade; its commit in sql/upgrade/releases.txt) to this version.
\set regress_db :DBNAME
-- tests/test_upgrade.py compares the whole catalog with a fresh install; this checks the route a DBA takes.
\set VERBOSITY terse
SET client_min_messages = warning;
CREATE DATABASE tgsis_installcheck_upgrade;
\c tgsis_installcheck_upgrade
SET client_min_messages = warning;
CREATE EXTENSION tgsis VERSION '0.2.0' CASCADE;
SELECT tgsis.create_storage() AS created;
SELECT (tgsis.register_feature_class('fault', 'SURFACE')).classname;
SELECT tgsis.new_geometry('SURFACE', 'f1', ARRAY[0, 0, 0, 1, 1, 0]::float8[], 0, 0) AS geoid \gset
INSERT INTO public.fault (_geoid) VALUES (:geoid);
ALTER EXTENSION tgsis UPDATE;
SELECT tgsis.version() = extversion AS version_matches FROM pg_extension WHERE extname = 'tgsis';
SELECT count(*) AS models FROM tgsis.data_models;
SELECT tablename FROM tgsis.model_tables WHERE to_regclass(format('tgsis.%I', tablename)) IS NULL;
SELECT c.relname FROM pg_depend d JOIN pg_class c ON c.oid = d.objid
 WHERE d.deptype = 'e' AND d.refobjid = (SELECT oid FROM pg_extension WHERE extname = 'tgsis')
   AND c.relname IN (SELECT tablename FROM tgsis.model_tables);
SELECT g.geoname, f._geoid = g.geoid AS kept FROM public.fault f JOIN tgsis.geometry g ON g.geoid = f._geoid;
SELECT version, method FROM tgsis.installation ORDER BY installed_at, version;
\c :regress_db
DROP DATABASE tgsis_installcheck_upgrade;
