-- tgsis.postgis_rows(class): the rows of a class's PostGIS view: each feature's columns, the instant (temporal classes) and its EWKB.
-- Why a function that reads the feature table through its name (dynamic SQL)
-- instead of a view that selects from it: a view on the feature table would
-- bind to that table, and feature versioning renames it to <class>_ver and
-- puts a view in its place (a plain view on it is refused, TG202). Read by
-- name, the rows are those of the caller's version, versioned or not.
-- Static classes: one row per feature; temporal classes: one per feature and
-- instant (tgsis.geometry_instants), its shape at that instant (left-closed:
-- the shape that holds from it on). Runs as the caller (readers may read).
CREATE FUNCTION tgsis.postgis_rows(p_class text)
RETURNS SETOF record
LANGUAGE plpgsql
STABLE
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_class tgsis.catalog := tgsis.catalog_row(p_class);
BEGIN
    IF v_class.timemodel = 'STATIC' THEN
        RETURN QUERY EXECUTE format('SELECT f.*, NULL::double precision, tgsis.ewkb_geometry(f._geoid, $1) FROM %I.%I f',
                                    v_class.schemaname, v_class.featuretable)
          USING v_class.srs;
    ELSE
        RETURN QUERY EXECUTE format('SELECT f.*, i.t, tgsis.ewkb_geometry_at(f._geoid, i.t, ''left'', $1)
                                       FROM %I.%I f CROSS JOIN LATERAL tgsis.geometry_instants(f._geoid) i',
                                    v_class.schemaname, v_class.featuretable)
          USING v_class.srs;
    END IF;
END
$$;

COMMENT ON FUNCTION tgsis.postgis_rows(text) IS
    'rows of a class''s PostGIS view (tgsis.create_postgis_view): the feature table''s columns, the instant (NULL for static classes) and the EWKB of the shape; reads the feature table by name, so that feature versioning can replace it';
