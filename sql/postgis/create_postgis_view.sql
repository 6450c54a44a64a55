-- tgsis.create_postgis_view(class): (re)create the view <class>_postgis: the class's features with a PostGIS geometry column geom.
-- Why: QGIS (and its 3D view) and PostGIS's own functions find layers as
-- relations with a geometry column whose type and SRID are declared (the
-- column's typmod, which geometry_columns reports): geom is
-- geometry(TINZ | POLYHEDRALSURFACEZ | MULTILINESTRINGZ | MULTIPOINTZ |
-- GEOMETRYCOLLECTIONZ, <class srs>). Created on request only, as it needs
-- PostGIS; it is no extension member and pg_dump dumps it (docs/postgis.md).
-- The view reads through tgsis.postgis_rows (which says why), with the
-- feature table's columns as they are now; temporal classes get one row per
-- feature and instant (_t). Readers may select it; it runs the functions as
-- the reader, so each sees their own version. It runs as tgsis's owner, who
-- owns the class's schema or is trusted there (register_feature_class), for
-- members of tgsis_admin; tgsis.drop_feature_class drops the view too.
CREATE FUNCTION tgsis.create_postgis_view(p_class text)
RETURNS regclass
LANGUAGE plpgsql
VOLATILE
SECURITY DEFINER
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_class   tgsis.catalog;
    v_ps      name;
    v_view    text;
    v_type    text;
    v_cols    text;
    v_defs    text;
    v_rel     regclass;
    v_column  record;
BEGIN
    IF NOT pg_has_role(tgsis.calling_role(), 'tgsis_admin', 'MEMBER') THEN
        RAISE EXCEPTION 'role % may not create PostGIS views of feature classes', tgsis.calling_role()
            USING ERRCODE = 'TG002', DETAIL = 'Creating views of feature classes is for members of tgsis_admin.',
                  HINT = format('a DBA may run: GRANT tgsis_admin TO %I', tgsis.calling_role());
    END IF;
    v_class := tgsis.catalog_row(p_class);
    IF v_class.geotype NOT IN ('MULTIPOINT', 'MULTILINESTRING', 'SURFACE', 'MULTITETRA', 'GEOMETRYCOLLECTION') THEN
        RAISE EXCEPTION 'feature class % holds % features, which have no PostGIS form', p_class, v_class.geotype
            USING ERRCODE = 'TG100',
                  HINT = 'PostGIS views exist for classes of MULTIPOINT, MULTILINESTRING, SURFACE, MULTITETRA and GEOMETRYCOLLECTION';
    END IF;
    v_ps := tgsis.postgis_schema();
    v_view := v_class.classname || '_postgis';
    v_type := CASE v_class.geotype WHEN 'SURFACE' THEN 'TINZ' WHEN 'MULTITETRA' THEN 'POLYHEDRALSURFACEZ'
                                   ELSE v_class.geotype || 'Z' END;
    v_rel := to_regclass(format('%I.%I', v_class.schemaname, v_view));
    -- only a view tgsis made (its owner, its comment) is replaced
    IF v_rel IS NOT NULL AND NOT (coalesce(obj_description(v_rel, 'pg_class'), '') LIKE 'tgsis PostGIS view %'
                                  AND (SELECT c.relkind = 'v' AND c.relowner = (SELECT relowner FROM pg_catalog.pg_class
                                                                               WHERE oid = 'tgsis.catalog'::regclass)
                                         FROM pg_catalog.pg_class c WHERE c.oid = v_rel)) THEN
        RAISE EXCEPTION 'relation %.% exists and is not the PostGIS view of class %', v_class.schemaname, v_view, p_class
            USING ERRCODE = 'TG201', HINT = format('rename or drop %I.%I, then call tgsis.create_postgis_view(%L) again',
                                                   v_class.schemaname, v_view, p_class);
    END IF;
    SELECT string_agg(format('r.%I', a.attname), ', ' ORDER BY a.attnum),
           string_agg(format('%I %s', a.attname, format_type(a.atttypid, a.atttypmod)), ', ' ORDER BY a.attnum)
      INTO v_cols, v_defs
      FROM pg_catalog.pg_attribute a
     WHERE a.attrelid = format('%I.%I', v_class.schemaname, v_class.featuretable)::regclass
       AND a.attnum > 0 AND NOT a.attisdropped;
    IF v_rel IS NOT NULL THEN   -- the columns may have changed: CREATE OR REPLACE VIEW cannot drop any
        EXECUTE format('DROP VIEW %s', v_rel);
    END IF;
    EXECUTE format('CREATE VIEW %I.%I AS SELECT %s, %s%I.st_geomfromewkb(r._ewkb)::%I.geometry(%s, %s) AS geom
                      FROM tgsis.postgis_rows(%L) AS r(%s, _t double precision, _ewkb bytea)',
                   v_class.schemaname, v_view, v_cols, CASE WHEN v_class.timemodel = 'STATIC' THEN '' ELSE 'r._t, ' END,
                   v_ps, v_ps, v_type, v_class.srs, v_class.classname, v_defs);
    v_rel := format('%I.%I', v_class.schemaname, v_view)::regclass;
    EXECUTE format('COMMENT ON VIEW %s IS %L', v_rel,
                   format('tgsis PostGIS view of feature class %s: its features with geom, a geometry(%s, %s)%s (tgsis.create_postgis_view)',
                          p_class, v_type, v_class.srs,
                          CASE WHEN v_class.timemodel = 'STATIC' THEN '' ELSE ', one row per feature and instant _t' END));
    FOR v_column IN
        SELECT a.attname, col_description(a.attrelid, a.attnum) AS note
          FROM pg_catalog.pg_attribute a
         WHERE a.attrelid = format('%I.%I', v_class.schemaname, v_class.featuretable)::regclass AND a.attnum > 0
           AND NOT a.attisdropped AND col_description(a.attrelid, a.attnum) IS NOT NULL
    LOOP
        EXECUTE format('COMMENT ON COLUMN %s.%I IS %L', v_rel, v_column.attname, v_column.note);
    END LOOP;
    EXECUTE format('COMMENT ON COLUMN %s.geom IS %L', v_rel,
                   format('the feature''s geometry (%s, SRID %s = the class''s srs; z up positive)%s', v_type, v_class.srs,
                          CASE WHEN v_class.timemodel = 'STATIC' THEN '' ELSE ' at instant _t' END));
    IF v_class.timemodel <> 'STATIC' THEN
        EXECUTE format('COMMENT ON COLUMN %s._t IS %L', v_rel,
                       'an instant of the feature (model time): the shape that holds from it on (left-closed)');
    END IF;
    EXECUTE format('GRANT SELECT ON %s TO tgsis_reader', v_rel);
    RETURN v_rel;
END
$$;

REVOKE ALL ON FUNCTION tgsis.create_postgis_view(text) FROM PUBLIC;
GRANT EXECUTE ON FUNCTION tgsis.create_postgis_view(text) TO tgsis_admin;

COMMENT ON FUNCTION tgsis.create_postgis_view(text) IS
    '(re)create <class>_postgis: the class''s features with geom, a PostGIS geometry(TINZ | POLYHEDRALSURFACEZ | ..., srs) column (temporal classes: one row per feature and instant _t), for QGIS and PostGIS queries; needs PostGIS (TG001), for tgsis_admin';
