-- tgsis.class_for_change(class, what): the catalog row of a class about to be edited, locked, for members of tgsis_admin.
-- tgsis.add_property, rename_property and drop_property start here: the
-- calling role must be a tgsis_admin (as for register_feature_class), and
-- the row lock makes two edits of one class wait for each other, so that
-- each reads the property lists the other one wrote.
CREATE FUNCTION tgsis.class_for_change(p_class text, p_what text)
RETURNS tgsis.catalog
LANGUAGE plpgsql
VOLATILE
AS $$
DECLARE
    v_class  tgsis.catalog;
    v_caller name := tgsis.calling_role();
BEGIN
    IF NOT pg_has_role(v_caller, 'tgsis_admin', 'MEMBER') THEN
        RAISE EXCEPTION 'role % may not % properties of feature classes', v_caller, p_what
            USING ERRCODE = 'TG002', DETAIL = 'Editing feature classes is for members of tgsis_admin.',
                  HINT = format('a DBA may run: GRANT tgsis_admin TO %I', v_caller);
    END IF;
    SELECT * INTO v_class FROM tgsis.catalog WHERE classname = p_class FOR UPDATE;
    IF NOT FOUND THEN
        RAISE EXCEPTION 'feature class % does not exist', coalesce(quote_literal(p_class), 'NULL')
            USING ERRCODE = 'TG200', HINT = 'SELECT classname FROM tgsis.catalog lists the classes';
    END IF;
    RETURN v_class;
END
$$;

COMMENT ON FUNCTION tgsis.class_for_change(text, text) IS
    'the tgsis.catalog row of a feature class, locked FOR UPDATE, after checking that the calling role is a tgsis_admin (TG002) and the class exists (TG200); the first step of add_property, rename_property and drop_property';
