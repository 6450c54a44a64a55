-- tgsis.forget_dropped(id): remove a tgsis.versioning_dropped row once what it records exists again.
-- Runs as tgsis's owner because only tgsis's definer code writes
-- tgsis.versioning_dropped; it removes a row only when the constraint (on the
-- recorded table) or the index (in the recorded schema) is there, so a call
-- cannot make tgsis forget a constraint that is still to be restored.
CREATE FUNCTION tgsis.forget_dropped(p_id integer)
RETURNS boolean
LANGUAGE plpgsql
VOLATILE
SECURITY DEFINER
SET search_path = pg_catalog, pg_temp
AS $$
BEGIN
    DELETE FROM tgsis.versioning_dropped d
     WHERE d.id = p_id
       AND CASE WHEN d.is_index
                THEN EXISTS (SELECT FROM pg_class c JOIN pg_namespace n ON n.oid = c.relnamespace
                              WHERE n.nspname = d.schemaname AND c.relname = d.name AND c.relkind = 'i')
                ELSE EXISTS (SELECT FROM pg_constraint con JOIN pg_class c ON c.oid = con.conrelid
                               JOIN pg_namespace n ON n.oid = c.relnamespace
                              WHERE n.nspname = d.schemaname AND c.relname = d.tablename AND con.conname = d.name) END;
    RETURN FOUND;
END
$$;

REVOKE ALL ON FUNCTION tgsis.forget_dropped(integer) FROM PUBLIC;

COMMENT ON FUNCTION tgsis.forget_dropped(integer) IS
    'remove a tgsis.versioning_dropped row whose constraint or index exists again (checked in the system catalogs); returns whether it did';
