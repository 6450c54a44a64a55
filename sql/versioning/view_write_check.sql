-- tgsis.view_write_check(): statement trigger on every versioned view: the write right on the session's version, once per statement.
-- SECURITY DEFINER so that roles writing the view need no right on schema
-- tgsis; the rights checked are the calling role's (tgsis.calling_role).
CREATE FUNCTION tgsis.view_write_check()
RETURNS trigger
LANGUAGE plpgsql
VOLATILE
SECURITY DEFINER
SET search_path = pg_catalog, pg_temp
AS $$
BEGIN
    PERFORM tgsis.write_revision();  -- TG002 without the write right, TG301 while viewing
    RETURN NULL;
END
$$;

COMMENT ON FUNCTION tgsis.view_write_check() IS
    'BEFORE statement trigger of versioned views: TG002 unless the calling role holds the write right on its session''s version (the row triggers then skip that check)';
