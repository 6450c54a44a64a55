-- make installcheck: feature versioning, a version with its own change, a saved revision, a merge.
\set VERBOSITY terse
SET client_min_messages = warning;
SELECT tgsis.enable_feature_versioning() > 0 AS versioned;
SELECT tgsis.create_version('survey2', 'DEFAULT', 'the second survey') > 0 AS created;
BEGIN;
SELECT tgsis.goto_version('survey2', true);
UPDATE tgsis.vrtx SET z = -5 WHERE vrtxid = 2;
UPDATE public.horizon SET unit = 'Jurassic';
SELECT z FROM tgsis.vrtx WHERE vrtxid = 2;
COMMIT;
SELECT tgsis.save_revision('survey2') > 0 AS saved;
-- DEFAULT does not see the change until the merge
SELECT z FROM tgsis.vrtx WHERE vrtxid = 2;
SELECT unit FROM public.horizon;
SELECT tgsis.merge_version('survey2') > 0 AS merged;
SELECT z FROM tgsis.vrtx WHERE vrtxid = 2;
SELECT unit FROM public.horizon;
SELECT name FROM tgsis.versions ORDER BY versionid;
-- a version name that is not one
\set VERBOSITY default
\set SHOW_CONTEXT never
SELECT tgsis.goto_version('no such version');
\echo :LAST_ERROR_SQLSTATE
