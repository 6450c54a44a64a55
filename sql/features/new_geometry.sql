-- tgsis.new_geometry(geotype, name, bounds, nvrtx, ncell, geoids, collection, timemodel, alive, color, zpositive, crs, metadata): insert a geometry row and return its geoid.
-- The client's write path calls it before copying vertices and simplices;
-- bounds is {xmin, ymin, zmin, xmax, ymax, zmax} (NULL: no vertex); a member
-- stored with its GEOMETRYCOLLECTION names the collection that owns it.
-- zpositive, crs and metadata record what the file meant (z convention,
-- coordinate-system block, other format facts): bounds are in elevation
-- whatever zpositive says, as the vertices are. p_class names the feature
-- class the geometry is stored for: a class registered without versioning
-- gets a geoid of no version (tgsis.claim_unversioned_geoid), and so do the
-- members of a collection that has one.
CREATE FUNCTION tgsis.new_geometry(
    p_geotype    text,
    p_name       text,
    p_bounds     double precision[],
    p_nvrtx      bigint,
    p_ncell      bigint,
    p_geoids     bigint[] DEFAULT NULL,
    p_collection bigint   DEFAULT NULL,
    p_timemodel  text     DEFAULT 'STATIC',
    p_alive      boolean  DEFAULT false,
    p_color      real[]   DEFAULT NULL,
    p_zpositive  text     DEFAULT NULL,
    p_crs        jsonb    DEFAULT NULL,
    p_metadata   jsonb    DEFAULT NULL,
    p_class      text     DEFAULT NULL)
RETURNS bigint
LANGUAGE plpgsql
SET search_path FROM CURRENT
AS $$
DECLARE
    v_geoid bigint;
    v_owner text;
    v_none  text;  -- the class without versioning the geometry belongs to, if any
BEGIN
    PERFORM tgsis.require_storage();  -- a bare CREATE EXTENSION: say what to run (geometry/require_storage.sql)
    PERFORM tgsis.plain_write_check('tgsis', 'geometry');  -- not "in" a version while features are plain
    -- geotypes and time models are the registered data models' (tgsis.data_models)
    IF NOT EXISTS (SELECT FROM tgsis.data_models m WHERE upper(p_geotype) = ANY (m.geotypes)) THEN
        RAISE EXCEPTION 'geotype % of a new geometry is unknown', coalesce(quote_literal(p_geotype), 'NULL')
            USING ERRCODE = 'TG102',
                  HINT = 'p_geotype => ' || tgsis.or_list(ARRAY(SELECT DISTINCT g FROM tgsis.data_models m, unnest(m.geotypes) AS g
                                                                 ORDER BY g));
    END IF;
    IF p_nvrtx IS NULL OR p_nvrtx < 0 OR p_ncell IS NULL OR p_ncell < 0 THEN
        RAISE EXCEPTION 'vertex and cell counts of a new geometry must be numbers >= 0, got p_nvrtx => % and p_ncell => %',
                        coalesce(p_nvrtx::text, 'NULL'), coalesce(p_ncell::text, 'NULL')
            USING ERRCODE = 'TG102', HINT = 'give the number of vertices and of cells (0 for none)';
    END IF;
    IF p_bounds IS NOT NULL AND (cardinality(p_bounds) <> 6 OR array_position(p_bounds, NULL) IS NOT NULL
                                 OR 'NaN' = ANY (p_bounds) OR 'Infinity' = ANY (p_bounds) OR '-Infinity' = ANY (p_bounds)) THEN
        RAISE EXCEPTION 'bounds of a new geometry must be 6 finite numbers {xmin, ymin, zmin, xmax, ymax, zmax}, got %', p_bounds
            USING ERRCODE = 'TG102';
    END IF;
    IF p_color IS NOT NULL AND (cardinality(p_color) <> 3 OR array_position(p_color, NULL) IS NOT NULL
                                OR EXISTS (SELECT FROM unnest(p_color) c WHERE NOT c BETWEEN 0 AND 1)) THEN
        RAISE EXCEPTION 'colour of a new geometry must be 3 numbers {red, green, blue} in [0, 1], got %', p_color
            USING ERRCODE = 'TG102';
    END IF;
    IF p_zpositive IS NOT NULL AND p_zpositive NOT IN ('Elevation', 'Depth') THEN
        RAISE EXCEPTION 'z convention % of a new geometry is unknown', quote_literal(p_zpositive)
            USING ERRCODE = 'TG102', HINT = 'p_zpositive => ''Elevation'' (up positive), ''Depth'' (down positive) or NULL';
    END IF;
    IF p_crs IS NOT NULL AND jsonb_typeof(p_crs) <> 'array' THEN
        RAISE EXCEPTION 'coordinate system of a new geometry must be a JSON array of the block''s lines, got %', jsonb_typeof(p_crs)
            USING ERRCODE = 'TG102', HINT = 'p_crs => ''["NAME Default", "ZPOSITIVE Depth"]'' or NULL';
    END IF;
    IF p_metadata IS NOT NULL AND jsonb_typeof(p_metadata) <> 'object' THEN
        RAISE EXCEPTION 'metadata of a new geometry must be a JSON object, got %', jsonb_typeof(p_metadata)
            USING ERRCODE = 'TG102', HINT = 'p_metadata => ''{}'' or NULL';
    END IF;
    IF NOT EXISTS (SELECT FROM tgsis.data_models m WHERE m.timemodel = upper(p_timemodel) AND upper(p_geotype) = ANY (m.geotypes)) THEN
        RAISE EXCEPTION 'time model % is not one of a % geometry', coalesce(quote_literal(p_timemodel), 'NULL'), upper(p_geotype)
            USING ERRCODE = 'TG102',
                  HINT = (SELECT string_agg(format('%s for %s', m.timemodel, tgsis.or_list(m.geotypes)), '; ' ORDER BY m.model)
                            FROM tgsis.data_models m WHERE m.model > 0);
    END IF;
    IF p_collection IS NOT NULL THEN
        IF upper(p_geotype) = 'GEOMETRYCOLLECTION' THEN
            RAISE EXCEPTION 'a GEOMETRYCOLLECTION cannot be a member of collection %: collections do not nest', p_collection
                USING ERRCODE = 'TG102', HINT = 'store the inner collection''s members in the outer one';
        END IF;
        SELECT geotype INTO v_owner FROM tgsis.geometry WHERE geoid = p_collection;
        IF NOT FOUND THEN
            RAISE EXCEPTION 'collection % of a new % geometry does not exist', p_collection, upper(p_geotype)
                USING ERRCODE = 'TG200';
        ELSIF v_owner <> 'GEOMETRYCOLLECTION' THEN
            RAISE EXCEPTION 'geometry % is a %, not a GEOMETRYCOLLECTION: it cannot own members', p_collection, v_owner
                USING ERRCODE = 'TG102';
        END IF;
    END IF;
    -- a feature of a class without versioning (or a member of one) takes a geoid of no version
    IF p_class IS NOT NULL AND NOT EXISTS (SELECT FROM tgsis.catalog c WHERE c.classname = p_class) THEN
        RAISE EXCEPTION 'feature class % of a new geometry does not exist', quote_literal(p_class)
            USING ERRCODE = 'TG200', HINT = 'SELECT classname FROM tgsis.catalog lists the classes';
    END IF;
    SELECT u.classname INTO v_none FROM tgsis.unversioned_features u WHERE u.geoid = p_collection;
    IF v_none IS NULL THEN
        SELECT c.classname INTO v_none FROM tgsis.catalog c WHERE c.classname = p_class AND NOT c.versioned;
    END IF;
    IF v_none IS NOT NULL THEN
        v_geoid := tgsis.claim_unversioned_geoid(v_none);
    ELSE
        v_geoid := nextval('tgsis.geometry_geoid_seq');
    END IF;
    INSERT INTO tgsis.geometry (geoid, geotype, geoname, geoids, collection, bbox, nvrtx, ncell, timemodel, alive,
                                colorred, colorgreen, colorblue, zpositive, crs, metadata)
    VALUES (v_geoid, upper(p_geotype), p_name, p_geoids, p_collection,
            CASE WHEN p_bounds IS NOT NULL THEN cube(p_bounds[1:3], p_bounds[4:6]) END,
            p_nvrtx, p_ncell, upper(p_timemodel), coalesce(p_alive, false), p_color[1], p_color[2], p_color[3],
            p_zpositive, p_crs, p_metadata)
    RETURNING geoid INTO v_geoid;
    RETURN v_geoid;
END
$$;

COMMENT ON FUNCTION tgsis.new_geometry(text, text, double precision[], bigint, bigint, bigint[], bigint, text, boolean, real[], text, jsonb, jsonb, text) IS
    'insert a tgsis.geometry row (bounding box from {xmin, ymin, zmin, xmax, ymax, zmax} in elevation; members of a GEOMETRYCOLLECTION name their owning collection; time model, alive, colour {r, g, b}; the file''s z convention, coordinate-system block and other format metadata; the feature class it is stored for, whose features may be of no version) and return its geoid';
