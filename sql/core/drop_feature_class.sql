-- tgsis.drop_feature_class(name, force): remove a feature class; with force also its features and their geometries.
-- The class's cell-property table is dropped whole, with the rows of collection members.
CREATE FUNCTION tgsis.drop_feature_class(p_name text, p_force boolean DEFAULT false)
RETURNS bigint
LANGUAGE plpgsql
AS $$
DECLARE
    v_class   tgsis.catalog;
    v_count   bigint;
    v_ids     bigint[];
    v_all     bigint[];
    v_geotype text;
BEGIN
    SELECT * INTO v_class FROM tgsis.catalog WHERE classname = p_name FOR UPDATE;
    IF NOT FOUND THEN
        RAISE EXCEPTION 'feature class % does not exist', coalesce(quote_literal(p_name), 'NULL')
            USING ERRCODE = 'TG200', HINT = 'SELECT classname FROM tgsis.catalog lists the classes';
    END IF;
    EXECUTE format('SELECT count(*), array_agg(_geoid) FROM %I.%I', v_class.schemaname, v_class.featuretable)
       INTO v_count, v_ids;
    IF v_count > 0 AND NOT p_force THEN
        RAISE EXCEPTION 'feature class % still has % feature(s)', p_name, v_count
            USING ERRCODE = 'TG202', HINT = 'delete them first, or drop with force => true to delete them with their geometries';
    END IF;
    IF v_count > 0 THEN
        -- the features' geometries and the collection members they own (not geometries a collection only lists)
        SELECT v_ids || coalesce(array_agg(geoid), '{}') INTO v_all FROM tgsis.geometry WHERE collection = ANY (v_ids);
        DELETE FROM tgsis.vrtx WHERE geoid = ANY (v_all);
        FOR v_geotype IN SELECT DISTINCT geotype FROM tgsis.geometry
                          WHERE geoid = ANY (v_all) AND geotype <> 'GEOMETRYCOLLECTION' LOOP
            EXECUTE format('DELETE FROM tgsis.%I WHERE geoid = ANY ($1)', tgsis.simplex_table(v_geotype)) USING v_all;
        END LOOP;
    END IF;
    EXECUTE format('DROP VIEW %I.%I', v_class.schemaname, v_class.viewname);
    EXECUTE format('DROP TABLE %I.%I', v_class.schemaname, v_class.cellprotable);
    EXECUTE format('DROP TABLE %I.%I', v_class.schemaname, v_class.featuretable);
    DELETE FROM tgsis.geometry WHERE geoid = ANY (v_all);
    DELETE FROM tgsis.catalog WHERE classname = p_name;
    RETURN v_count;
END
$$;

COMMENT ON FUNCTION tgsis.drop_feature_class(text, boolean) IS
    'drop a feature class and its tables; refuses (TG202) while features exist unless force, which deletes them and their geometries (with the members collections own); returns the number of features deleted';
