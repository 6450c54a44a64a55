-- tgsis.get_working_revision(): the working revision of the session's working version.
CREATE FUNCTION tgsis.get_working_revision()
RETURNS integer
LANGUAGE sql
STABLE
AS $$
    SELECT s[cardinality(s)] FROM (SELECT tgsis.get_revisions(false)) AS w(s)
$$;

COMMENT ON FUNCTION tgsis.get_working_revision() IS
    'the working revision of the session''s working version: the revision its changes are labelled with';
