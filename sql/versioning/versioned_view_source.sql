-- tgsis.versioned_view_source(schema, table, columns): the CREATE VIEW statement of a versioned table's view.
-- get_revisions() sits in scalar subqueries so that it runs once per query
-- (in the WHERE clause directly it would run once per row). Measured on
-- PostgreSQL 15 (bench/versioning.py), two choices of form:
--   * (revision = ANY (...)) IS TRUE keeps the revision test out of index
--     conditions: as an index condition on a non-leading column, btree runs
--     one index scan per revision in the set (4-6x the index work of a
--     one-object fetch); as a filter it costs a few ns per row;
--   * most rows are live (lastrevs empty): the stored flag revclosed spares
--     them the array overlap test, and reading the array at all (a short
--     array is copied out of the row to be read): 30-40 % of a full scan.
CREATE FUNCTION tgsis.versioned_view_source(p_schema text, p_table text, p_columns text[])
RETURNS text
LANGUAGE sql
IMMUTABLE
PARALLEL SAFE
AS $$
    SELECT format('CREATE VIEW %I.%I AS SELECT %s FROM %I.%I v WHERE %s',
                  p_schema, p_table,
                  (SELECT string_agg(format('v.%I', c), ', ' ORDER BY o) FROM unnest(p_columns) WITH ORDINALITY AS u(c, o)),
                  p_schema, p_table || '_ver', tgsis.visible_versions('v', '(SELECT tgsis.get_revisions(true))::integer[]'))
$$;

COMMENT ON FUNCTION tgsis.versioned_view_source(text, text, text[]) IS
    'source of the view <table> over <table>_ver that shows the rows of the session''s viewing revision set';
