-- tgsis.enable_versioning(table, objectkeyfield, objectclass, iudorder, shortname): version a table in place.
-- The table (name or schema.name, found in the caller's search_path) keeps
-- its name and columns for applications: see tgsis.enable_versioning_rel.
CREATE FUNCTION tgsis.enable_versioning(
    p_table          text,
    p_objectkeyfield text,
    p_objectclass    text,
    p_iudorder       integer DEFAULT 0,
    p_shortname      text    DEFAULT NULL)
RETURNS tgsis.versioned_tables
LANGUAGE plpgsql
VOLATILE
AS $$
BEGIN
    RETURN tgsis.enable_versioning_rel(tgsis.resolve_table(p_table), p_objectkeyfield, p_objectclass, p_iudorder, p_shortname);
END
$$;

COMMENT ON FUNCTION tgsis.enable_versioning(text, text, text, integer, text) IS
    'version a table: storage renamed <table>_ver (+ revision, lastrevs), a view <table> with INSTEAD OF triggers takes its place; registered in tgsis.versioned_tables';
