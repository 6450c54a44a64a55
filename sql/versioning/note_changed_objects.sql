-- tgsis.note_changed_objects(schema, table, revision, keys): note in tgsis.revision_objects the objects a writer of storage changes in a revision.
-- For tgsis's own set-based writers (copy_object_state, close_object_rows)
-- and its trigger functions; the views' triggers go through
-- tgsis.record_changed_objects. Keys already noted for the revision (by this
-- transaction or a committed one) are not noted again; revision 0 is not
-- noted at all (tgsis.revision_objects says why).
CREATE FUNCTION tgsis.note_changed_objects(p_schema text, p_table text, p_revision integer, p_keys text[])
RETURNS void
LANGUAGE sql
VOLATILE
AS $$
    INSERT INTO tgsis.revision_objects (revision, schemaname, tablename, objectkey)
    SELECT p_revision, p_schema, p_table, d.k
      FROM (SELECT DISTINCT u.k FROM pg_catalog.unnest(p_keys) AS u(k) WHERE u.k IS NOT NULL) AS d
     WHERE p_revision <> 0
       AND NOT EXISTS (SELECT FROM tgsis.revision_objects o
                        WHERE o.revision = p_revision AND o.schemaname = p_schema AND o.tablename = p_table
                          AND o.objectkey = d.k)
$$;

REVOKE ALL ON FUNCTION tgsis.note_changed_objects(text, text, integer, text[]) FROM PUBLIC;

COMMENT ON FUNCTION tgsis.note_changed_objects(text, text, integer, text[]) IS
    'note objects (keys as text) of a versioned table as changed in a revision (tgsis.revision_objects), unless noted already; for tgsis''s own writers of storage';
