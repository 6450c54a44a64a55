-- tgsis.versioned_table(view): the catalog row of a versioned table (its view), or TG200.
CREATE FUNCTION tgsis.versioned_table(p_table regclass)
RETURNS tgsis.versioned_tables
LANGUAGE plpgsql
STABLE
AS $$
DECLARE
    v_row tgsis.versioned_tables;
BEGIN
    SELECT t.* INTO v_row
      FROM tgsis.versioned_tables t
      JOIN pg_catalog.pg_class c ON c.relname = t.tablename
      JOIN pg_catalog.pg_namespace n ON n.oid = c.relnamespace AND n.nspname = t.schemaname
     WHERE c.oid = p_table;
    IF NOT FOUND THEN
        RAISE EXCEPTION 'table % is not versioned', coalesce(p_table::text, 'NULL')
            USING ERRCODE = 'TG200', HINT = 'SELECT * FROM tgsis.versioned_tables lists the versioned tables';
    END IF;
    RETURN v_row;
END
$$;

COMMENT ON FUNCTION tgsis.versioned_table(regclass) IS
    'catalog row (tgsis.versioned_tables) of a versioned table, given as its view; raises TG200 if it is not versioned';
