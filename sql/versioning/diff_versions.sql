-- tgsis.diff_versions(a, b, a_revision, b_revision): objects whose rows differ between two versions (or revisions).
-- tgsis.diff_table over every versioned table, in the order of the classes and
-- their tables, in one statement (one snapshot); see there for what differs.
-- The versions are checked first, so that a wrong name is an error even
-- before any table is versioned.
CREATE FUNCTION tgsis.diff_versions(
    p_a          text,
    p_b          text,
    p_a_revision integer DEFAULT NULL,
    p_b_revision integer DEFAULT NULL)
RETURNS TABLE (objectclass text, objectkey text, shortname text, added bigint, removed bigint, changed bigint)
LANGUAGE plpgsql
STABLE
AS $$
DECLARE
    v_t tgsis.versioned_tables;
BEGIN
    PERFORM tgsis.revision_set(tgsis.version_id(p_a), p_a_revision), tgsis.revision_set(tgsis.version_id(p_b), p_b_revision);
    FOR v_t IN SELECT * FROM tgsis.versioned_tables ORDER BY objectclass, iudorder, shortname LOOP
        RETURN QUERY SELECT * FROM tgsis.diff_table(format('%I.%I', v_t.schemaname, v_t.tablename)::regclass,
                                                    p_a, p_b, p_a_revision, p_b_revision);
    END LOOP;
END
$$;

COMMENT ON FUNCTION tgsis.diff_versions(text, text, integer, integer) IS
    'objects whose rows differ from version a (at a revision) to version b: per table, rows added, removed and changed (by row key and values); tgsis.diff_table over every versioned table';
