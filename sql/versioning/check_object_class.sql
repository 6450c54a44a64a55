-- tgsis.check_object_class(objectclass): TG200 unless some versioned table belongs to the object class.
CREATE FUNCTION tgsis.check_object_class(p_objectclass text)
RETURNS void
LANGUAGE plpgsql
STABLE
AS $$
BEGIN
    IF NOT EXISTS (SELECT FROM tgsis.versioned_tables WHERE objectclass = p_objectclass) THEN
        RAISE EXCEPTION 'object class % does not exist', coalesce(quote_literal(p_objectclass), 'NULL')
            USING ERRCODE = 'TG200', HINT = 'SELECT DISTINCT objectclass FROM tgsis.versioned_tables lists them';
    END IF;
END
$$;

COMMENT ON FUNCTION tgsis.check_object_class(text) IS 'raise TG200 naming the object class unless a versioned table belongs to it';
