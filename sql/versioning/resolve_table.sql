-- tgsis.resolve_table(name): the relation a name ('t' or 'schema.t') means in the caller's search_path, or TG200.
CREATE FUNCTION tgsis.resolve_table(p_table text)
RETURNS regclass
LANGUAGE plpgsql
STABLE
AS $$
DECLARE
    v_rel regclass;
BEGIN
    BEGIN
        v_rel := to_regclass(p_table);
    EXCEPTION WHEN invalid_name OR syntax_error OR feature_not_supported THEN  -- malformed names; db.schema.name
        v_rel := NULL;
    END;
    IF v_rel IS NULL THEN
        RAISE EXCEPTION 'table % does not exist', coalesce(quote_literal(p_table), 'NULL')
            USING ERRCODE = 'TG200', HINT = 'give it as name or schema.name, as it would be written in SQL';
    END IF;
    RETURN v_rel;
END
$$;

COMMENT ON FUNCTION tgsis.resolve_table(text) IS
    'the relation a table name (''t'' or ''schema.t'', quoted where SQL needs it) means in the caller''s search_path; raises TG200 if none';
