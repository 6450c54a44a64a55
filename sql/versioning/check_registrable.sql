-- tgsis.check_registrable(schema, table, owner): may tgsis record facts about this table for the calling role? Else TG002.
-- The definer functions that write tgsis.versioned_tables and
-- tgsis.versioning_dropped run as tgsis's owner, and other definer code later
-- acts on what those rows name. So a row may name only a table the calling
-- role owns (pg_has_role USAGE: it is, or acts as, a member of the owner), or
-- one tgsis itself created: owned by tgsis's owner (the owner of
-- tgsis.versioned_tables) and in schema tgsis or listed in tgsis.catalog,
-- which only tgsis's definer code writes. Another table of tgsis's owner (a
-- superuser's table, when tgsis's owner is that superuser) is not tgsis's.
CREATE FUNCTION tgsis.check_registrable(p_schema text, p_table text, p_owner oid)
RETURNS void
LANGUAGE plpgsql
STABLE
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_tgsis_owner oid := (SELECT relowner FROM pg_class WHERE oid = 'tgsis.versioned_tables'::regclass);
BEGIN
    IF p_owner IS NOT NULL AND pg_has_role(tgsis.calling_role(), p_owner, 'USAGE') THEN
        RETURN;
    END IF;
    IF p_owner = v_tgsis_owner
       AND (p_schema = 'tgsis'
            OR EXISTS (SELECT FROM tgsis.class_tables c WHERE c.schemaname = p_schema AND c.tablename = p_table)) THEN
        RETURN;
    END IF;
    RAISE EXCEPTION 'role % does not own %.%, and tgsis did not create it', tgsis.calling_role(), p_schema, p_table
        USING ERRCODE = 'TG002',
              DETAIL = format('Its owner is %s. tgsis records and later acts on tables their owners version, or its own.',
                              coalesce(pg_get_userbyid(p_owner)::text, 'unknown')),
              HINT = 'only the table''s owner may version it (or make it plain again)';
END
$$;

COMMENT ON FUNCTION tgsis.check_registrable(text, text, oid) IS
    'raise TG002 unless the calling role owns the table (through membership) or tgsis created it (owned by tgsis''s owner, in schema tgsis or listed in tgsis.catalog): what definer code may record in versioned_tables and versioning_dropped';
