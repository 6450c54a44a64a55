-- tgsis.claim_unversioned_geoid(class): a new geoid for a feature (or collection member) of a class without versioning.
-- The geoid comes from tgsis.geometry's own sequence and is recorded in
-- tgsis.unversioned_features before any row carries it, so that every writer
-- of shared storage sees it as a key of no version from its first row.
-- SECURITY DEFINER (the registry is tgsis's alone); it hands out the number
-- itself, so a caller can mark neither a geometry that exists nor the next
-- one of another session. The calling role must be allowed to add features
-- to the class (INSERT on its feature table), and the session must be in
-- DEFAULT's working revision (tgsis.unversioned_revision, TG305).
CREATE FUNCTION tgsis.claim_unversioned_geoid(p_class text)
RETURNS bigint
LANGUAGE plpgsql
VOLATILE
SECURITY DEFINER
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_class tgsis.catalog;
    v_geoid bigint;
BEGIN
    SELECT * INTO v_class FROM tgsis.catalog c WHERE c.classname = p_class FOR SHARE;  -- not dropped meanwhile
    IF NOT FOUND THEN
        RAISE EXCEPTION 'feature class % does not exist', coalesce(quote_literal(p_class), 'NULL')
            USING ERRCODE = 'TG200', HINT = 'SELECT classname FROM tgsis.catalog lists the classes';
    END IF;
    IF v_class.versioned THEN
        RAISE EXCEPTION 'feature class % is versioned: its features take geoids of their own', p_class
            USING ERRCODE = 'TG300', HINT = 'only classes registered without versioning have features of no version';
    END IF;
    IF NOT has_table_privilege(tgsis.calling_role(), format('%I.%I', v_class.schemaname, v_class.featuretable), 'INSERT') THEN
        RAISE EXCEPTION 'role % may not add features to class %', quote_ident(tgsis.calling_role()), p_class
            USING ERRCODE = 'TG002', HINT = format('its owner can GRANT INSERT ON %I.%I', v_class.schemaname, v_class.featuretable);
    END IF;
    v_geoid := nextval('tgsis.geometry_geoid_seq');
    INSERT INTO tgsis.unversioned_features (geoid, classname) VALUES (v_geoid, p_class);
    PERFORM tgsis.unversioned_revision(ARRAY[v_geoid]);  -- TG305 outside DEFAULT's working revision (the error undoes the claim)
    RETURN v_geoid;
END
$$;

COMMENT ON FUNCTION tgsis.claim_unversioned_geoid(text) IS
    'a new geoid recorded in tgsis.unversioned_features for a feature of a class without versioning (callers with INSERT on its feature table, in DEFAULT''s working revision: TG305 elsewhere)';
