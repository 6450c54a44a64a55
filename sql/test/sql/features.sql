-- make installcheck: a feature class, a surface stored by SQL, its box, checks and refusals.
\set VERBOSITY terse
SET client_min_messages = warning;
SELECT classname, geotype, featuretable, cellprotable
  FROM tgsis.register_feature_class('horizon', 'SURFACE', '[{"name": "unit", "type": "text"}]',
                                    '[{"name": "depth", "type": "double precision"}]');
WITH g AS (SELECT tgsis.new_geometry('SURFACE', 'top', ARRAY[0, 0, 0, 1, 1, 0]::float8[], 3, 1) AS geoid),
     v AS (INSERT INTO tgsis.vrtx SELECT geoid, i, i % 2, i / 2, 0 FROM g, generate_series(0, 2) i),
     t AS (INSERT INTO tgsis.trgl SELECT geoid, 0, 0, 1, 2 FROM g),
     p AS (INSERT INTO public.horizon_cellpros SELECT geoid, i, 10 * i FROM g, generate_series(0, 2) i)
INSERT INTO public.horizon (_geoid, unit) SELECT geoid, 'Triassic' FROM g;
SELECT nvrtx, ncell, bbox FROM tgsis.refresh_geometry((SELECT _geoid FROM public.horizon));
SELECT problem, count FROM tgsis.check_geometry((SELECT _geoid FROM public.horizon));
SELECT count(*) AS in_box FROM tgsis.geometries_in_box(0.5, 0.5, -1, 2, 2, 1);
SELECT count(*) AS outside FROM tgsis.geometries_in_box(5, 5, 5, 6, 6, 6);
SELECT unit, count(*) FROM public.horizon_v GROUP BY unit;
-- a broken surface is reported, naming the problem
INSERT INTO tgsis.trgl SELECT _geoid, 1, 0, 1, 7 FROM public.horizon;
SELECT problem, count, example FROM tgsis.check_geometry((SELECT _geoid FROM public.horizon));
DELETE FROM tgsis.trgl WHERE trglid = 1;
-- bad input: our SQLSTATE, a message naming it, a hint
\set VERBOSITY default
\set SHOW_CONTEXT never
SELECT tgsis.register_feature_class('horizon', 'SURFACE');
\echo :LAST_ERROR_SQLSTATE
SELECT tgsis.register_feature_class('bad', 'BLOB');
\echo :LAST_ERROR_SQLSTATE
SELECT count(*) AS classes FROM tgsis.catalog;
