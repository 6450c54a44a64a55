-- tgsis.record_changed_objects(schema, table, keys): note objects a write through a versioned view changes in the session's working revision.
-- Called by the views' INSTEAD OF triggers (tgsis.versioning_trigger_source),
-- which run as each table's owner, when their probe of tgsis.revision_objects
-- finds an object not yet noted in the working revision: once per object and
-- revision, not per row. The revision is the session's working one, where
-- the calling role holds the write right (tgsis.write_revision: TG002,
-- TG301), so nobody can note objects in another version's revisions; a note
-- of an object that did not change is only a key a merge looks at and finds
-- unchanged.
CREATE FUNCTION tgsis.record_changed_objects(p_schema text, p_table text, p_keys text[])
RETURNS void
LANGUAGE plpgsql
VOLATILE
SECURITY DEFINER
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_revision integer;
BEGIN
    IF NOT EXISTS (SELECT FROM tgsis.versioned_tables t WHERE t.schemaname = p_schema AND t.tablename = p_table) THEN
        RAISE EXCEPTION 'table %.% is not versioned', coalesce(quote_ident(p_schema), 'NULL'),
                coalesce(quote_ident(p_table), 'NULL')
            USING ERRCODE = 'TG200', HINT = 'SELECT * FROM tgsis.versioned_tables lists the versioned tables';
    END IF;
    SELECT w.revision INTO v_revision FROM tgsis.write_revision() AS w;
    PERFORM tgsis.note_changed_objects(p_schema, p_table, v_revision, p_keys);
END
$$;

COMMENT ON FUNCTION tgsis.record_changed_objects(text, text, text[]) IS
    'note objects (keys as text) of a versioned table as changed in the session''s working revision (tgsis.revision_objects), which the calling role must be allowed to write; called by the versioned views'' write triggers';
