-- tgsis.versioned_view_source(schema, table, columns): the CREATE VIEW statement of a versioned table's view.
-- get_revisions() sits in scalar subqueries so that it runs once per query
-- (in the WHERE clause directly it would run once per row), and the
-- predicate stays indexable: revision = ANY(...) is an index condition.
CREATE FUNCTION tgsis.versioned_view_source(p_schema text, p_table text, p_columns text[])
RETURNS text
LANGUAGE sql
IMMUTABLE
PARALLEL SAFE
AS $$
    SELECT format('CREATE VIEW %I.%I AS SELECT %s FROM %I.%I v '
                  'WHERE v.revision = ANY ((SELECT tgsis.get_revisions(true))::integer[]) '
                  'AND NOT (v.lastrevs && (SELECT tgsis.get_revisions(true)))',
                  p_schema, p_table,
                  (SELECT string_agg(format('v.%I', c), ', ' ORDER BY o) FROM unnest(p_columns) WITH ORDINALITY AS u(c, o)),
                  p_schema, p_table || '_ver')
$$;

COMMENT ON FUNCTION tgsis.versioned_view_source(text, text, text[]) IS
    'source of the view <table> over <table>_ver that shows the rows of the session''s viewing revision set';
