-- tgsis.visible_versions(alias, set): the visibility predicate of stored versions, as SQL text.
-- The one text of "a version (a row version of <table>_ver, a chunk version of
-- <table>_chunk) that the revision set sees": made in a revision of the set,
-- and either still live or closed in no revision of the set. Every reader of
-- versions builds its WHERE clause from it (the versioned views, the chunk
-- faces, the versioning triggers, rows_at, the model readers of chunks, the
-- G-map chunk reader); a reader with a static query keeps the same text,
-- compared with this function's by tests/test_visible_versions.py so that they
-- cannot drift. The two choices of form are tgsis.versioned_view_source's
-- (measured there): (revision = ANY (set)) IS TRUE keeps the revision test out
-- of index conditions, and the stored flag revclosed spares live versions the
-- array overlap test. p_alias is the versions' range variable (quoted as an
-- identifier); p_set an SQL expression of type integer[] (code, not a value:
-- a parameter such as $2, a variable, a scalar subquery), written twice; a
-- scalar subquery takes a cast, (SELECT tgsis.get_revisions(true))::integer[]:
-- bare, ANY ((SELECT ...)) is read as ANY (subquery), integer = integer[].
-- Executable by PUBLIC (text only, no data read): the invoker readers that
-- build their queries from it run as their callers.
CREATE FUNCTION tgsis.visible_versions(p_alias text, p_set text)
RETURNS text
LANGUAGE sql
IMMUTABLE
PARALLEL SAFE
AS $$
    SELECT format('(%1$I.revision = ANY (%2$s)) IS TRUE AND (NOT %1$I.revclosed OR NOT (%1$I.lastrevs && %2$s))',
                  p_alias, p_set)
$$;

COMMENT ON FUNCTION tgsis.visible_versions(text, text) IS
    'the visibility predicate of stored versions as SQL text, for range variable p_alias and the revision set expression p_set (integer[], written twice): (revision = ANY (set)) IS TRUE AND (NOT revclosed OR NOT (lastrevs && set)); the one text every reader of row and chunk versions builds its WHERE clause from';
