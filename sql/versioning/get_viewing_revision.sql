-- tgsis.get_viewing_revision(): the older revision the session looks at (setting tgsis.revision), NULL for none.
CREATE FUNCTION tgsis.get_viewing_revision()
RETURNS integer
LANGUAGE plpgsql
STABLE
PARALLEL SAFE
AS $$
DECLARE
    v_text text := nullif(btrim(current_setting('tgsis.revision', true)), '');
BEGIN
    IF v_text IS NULL THEN
        RETURN NULL;
    END IF;
    IF v_text !~ '^[0-9]{1,9}$' THEN
        RAISE EXCEPTION 'setting tgsis.revision is %, not a revision number', quote_literal(v_text)
            USING ERRCODE = 'TG100', HINT = 'SELECT tgsis.goto_version(tgsis.get_working_version()) clears it';
    END IF;
    RETURN v_text::integer;
END
$$;

COMMENT ON FUNCTION tgsis.get_viewing_revision() IS
    'the revision the session views instead of its working revision (setting tgsis.revision, set by goto_revision); NULL when none';
