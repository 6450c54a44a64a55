-- tgsis.chosen_storage(): how model tables registered for chunks are stored when tgsis creates them or an upgrade switches them: 'chunks' (the default) or 'rows'.
-- Chunks are the default storage of model 1 (issue 40, docs/storage.md); an
-- install may keep rows. The choice is the custom setting tgsis.storage, so
-- that both install routes honour it the same way: tgsis.install (and `tgsis db
-- install --storage`) sets it for its transaction, and the plain-SQL script,
-- CREATE EXTENSION followed by tgsis.create_storage(), and the upgrade script
-- read it from the session (`SET tgsis.storage = rows` in psql first). Unset
-- or empty: chunks. Any other value is refused by name (TG001) before
-- anything is created: a typo must not give the storage nobody asked for.
CREATE FUNCTION tgsis.chosen_storage()
RETURNS text
LANGUAGE plpgsql
STABLE
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_value text := nullif(btrim(current_setting('tgsis.storage', true)), '');
BEGIN
    IF v_value IS NULL THEN
        RETURN 'chunks';
    END IF;
    IF lower(v_value) NOT IN ('chunks', 'rows') THEN
        RAISE EXCEPTION 'the setting tgsis.storage is %, which names no storage', quote_literal(v_value)
            USING ERRCODE = 'TG001',
                  DETAIL = 'tgsis.storage says how the model tables registered for chunks are stored when created or upgraded: chunks (the default) or rows.',
                  HINT = 'in psql: SET tgsis.storage = chunks (or rows), or RESET tgsis.storage';
    END IF;
    RETURN lower(v_value);
END
$$;

REVOKE ALL ON FUNCTION tgsis.chosen_storage() FROM PUBLIC;

COMMENT ON FUNCTION tgsis.chosen_storage() IS
    'the storage of the model tables registered for chunks that tgsis.create_storage creates and the upgrade switches: the setting tgsis.storage, chunks (the default, unset or empty) or rows; TG001 for any other value';
