-- tgsis.catalog_row(class): the catalog row of a feature class, or TG200 naming it.
CREATE FUNCTION tgsis.catalog_row(p_class text)
RETURNS tgsis.catalog
LANGUAGE plpgsql
STABLE
AS $$
DECLARE
    v_class tgsis.catalog;
BEGIN
    SELECT * INTO v_class FROM tgsis.catalog WHERE classname = p_class;
    IF NOT FOUND THEN
        RAISE EXCEPTION 'feature class % does not exist', coalesce(quote_literal(p_class), 'NULL')
            USING ERRCODE = 'TG200', HINT = 'SELECT classname FROM tgsis.catalog lists the classes';
    END IF;
    RETURN v_class;
END
$$;

COMMENT ON FUNCTION tgsis.catalog_row(text) IS 'the tgsis.catalog row of a feature class; raises TG200 when there is none';
