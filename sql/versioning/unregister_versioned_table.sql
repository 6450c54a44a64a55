-- tgsis.unregister_versioned_table(schema, table): forget a versioned table that disable_versioning has just made plain.
-- Runs as tgsis's owner because only tgsis's definer code writes
-- tgsis.versioned_tables; it removes a row only when the system catalogs say
-- it is no longer true (<table> is a plain table again and <table>_ver is
-- gone; for a model table stored in chunks: its face has no write-right check
-- of versioning left, tgsis.disable_versioning_rel), so a call can only remove
-- stale rows. The notes of its changed
-- objects (tgsis.revision_objects) go with it.
CREATE FUNCTION tgsis.unregister_versioned_table(p_schema text, p_table text)
RETURNS boolean
LANGUAGE plpgsql
VOLATILE
SECURITY DEFINER
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_rel   regclass := to_regclass(format('%I.%I', p_schema, p_table));
    v_still boolean;
BEGIN
    IF tgsis.stored_in_chunks(p_schema, p_table) THEN
        v_still := EXISTS (SELECT FROM pg_trigger tr WHERE tr.tgrelid = v_rel AND tr.tgname = 'tgsis_versioning_rights');
    ELSE
        v_still := v_rel IS NULL OR (SELECT relkind FROM pg_class WHERE oid = v_rel) NOT IN ('r', 'p')
                   OR to_regclass(format('%I.%I', p_schema, p_table || '_ver')) IS NOT NULL;
    END IF;
    IF v_still THEN
        RAISE EXCEPTION '%.% is still versioned (or gone): its registration stays', p_schema, p_table
            USING ERRCODE = 'TG202', HINT = 'tgsis.disable_versioning makes a versioned table plain and forgets it';
    END IF;
    DELETE FROM tgsis.revision_objects WHERE schemaname = p_schema AND tablename = p_table;
    DELETE FROM tgsis.versioned_tables WHERE schemaname = p_schema AND tablename = p_table;
    RETURN FOUND;
END
$$;

REVOKE ALL ON FUNCTION tgsis.unregister_versioned_table(text, text) FROM PUBLIC;

COMMENT ON FUNCTION tgsis.unregister_versioned_table(text, text) IS
    'remove the tgsis.versioned_tables row of a table that is plain again (checked in the system catalogs); returns whether there was one';
