-- tgsis.version_id(name): id of a version, or TG200 naming it.
CREATE FUNCTION tgsis.version_id(p_name text)
RETURNS integer
LANGUAGE plpgsql
STABLE
AS $$
DECLARE
    v_id integer;
BEGIN
    SELECT versionid INTO v_id FROM tgsis.versions WHERE name = p_name;
    IF NOT FOUND THEN
        RAISE EXCEPTION 'version % does not exist', coalesce(quote_literal(p_name), 'NULL')
            USING ERRCODE = 'TG200', HINT = 'SELECT name FROM tgsis.versions lists the versions';
    END IF;
    RETURN v_id;
END
$$;

COMMENT ON FUNCTION tgsis.version_id(text) IS 'id of the version with that name; raises TG200 when there is none';
