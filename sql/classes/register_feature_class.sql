-- tgsis.register_feature_class(...): create a feature class (feature table, cell-property table, view) and catalog it.
-- A temporal class (time model INSTANTS = model 2, EVOLVING = model 3) holds
-- SURFACE features; it gets a per-instant property table <name>_pros, and the
-- time keys (_times, or _timem and _timet) in it and in <name>_cellpros.
-- It runs as tgsis's owner (SECURITY DEFINER), so that the class's tables,
-- views and generated functions are objects tgsis itself created: the
-- definer code that later versions them (enable_feature_versioning) acts only
-- on tables tgsis.catalog names, and only tgsis's definer code writes that.
-- The calling role must be a tgsis_admin with CREATE on the target schema; the
-- system schemas and tgsis's own are refused, and so are schemas of other
-- owners than tgsis's or a superuser (they could replace the class's tables).
-- Versioning is chosen per class (docs/versioning.md, "Versioning per
-- class"): by default (p_versioned NULL or true) a class is versioned with
-- every class while feature versioning is on (p_versioned => true while it
-- is off is refused); p_versioned => false registers a class without
-- versioning, before or after tgsis.enable_feature_versioning: its tables
-- stay plain and its features' rows in the storage every class shares are
-- rows of no version (tgsis.unversioned_features).
-- Storage: a STATIC class's property tables are made in chunks when model 1
-- is stored in chunks in this database and tgsis.storage is not rows
-- (tgsis.chunk_class_by_default; docs/storage.md, "Property chunks by
-- default: the rule"); a temporal class's, or any under tgsis.storage = rows,
-- are rows.
CREATE FUNCTION tgsis.register_feature_class(
    p_name               text,
    p_geotype            text,
    p_feature_properties jsonb   DEFAULT '[]',
    p_cell_properties    jsonb   DEFAULT '[]',
    p_proalignment       text    DEFAULT 'VERTEX',
    p_srs                integer DEFAULT 0,
    p_schema             text    DEFAULT 'public',
    p_description        text    DEFAULT NULL,
    p_time_model         text    DEFAULT 'STATIC',
    p_instant_properties jsonb   DEFAULT '[]',
    p_time_unit          text    DEFAULT NULL,
    p_cell_level         integer DEFAULT NULL,
    p_versioned          boolean DEFAULT NULL)
RETURNS tgsis.catalog
LANGUAGE plpgsql
VOLATILE
SECURITY DEFINER
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_geotype   text := upper(btrim(p_geotype));
    v_align     text := upper(btrim(p_proalignment));
    v_cellpros  text := p_name || '_cellpros';
    v_view      text := p_name || '_v';
    v_model     text := upper(btrim(p_time_model));
    v_dm        tgsis.data_models;
    v_temporal  boolean;
    v_pros      text;
    v_timekey   text;
    v_icols     text;
    v_iprops    jsonb;
    v_fcols     text;
    v_ccols     text;
    v_ocols     text;
    v_other     text;
    v_notnull   text;
    v_fprops    jsonb;
    v_cprops    jsonb;
    v_row       tgsis.catalog;
    v_caller    name := tgsis.calling_role();
    v_nspowner  oid;
BEGIN
    PERFORM tgsis.require_storage();  -- a bare CREATE EXTENSION: say what to run (geometry/require_storage.sql)
    IF NOT pg_has_role(v_caller, 'tgsis_admin', 'MEMBER') THEN
        RAISE EXCEPTION 'role % may not register feature classes', v_caller
            USING ERRCODE = 'TG002', DETAIL = 'Registering feature classes is for members of tgsis_admin.',
                  HINT = format('a DBA may run: GRANT tgsis_admin TO %I', v_caller);
    END IF;
    IF p_versioned AND NOT EXISTS (SELECT FROM tgsis.versioned_tables WHERE schemaname = 'tgsis' AND tablename = 'geometry') THEN
        RAISE EXCEPTION 'feature class % cannot be versioned on its own: feature versioning is off', coalesce(quote_literal(p_name), 'NULL')
            USING ERRCODE = 'TG300',
                  DETAIL = 'Classes are versioned with the geometries of every data model, or none.',
                  HINT = 'SELECT tgsis.enable_feature_versioning() versions model 1 and every feature class not registered '
                         'with p_versioned => false';
    END IF;
    IF p_name IS NULL OR p_name !~ '^[a-z][a-z0-9_]*$' OR quote_ident(p_name) <> p_name OR length(v_cellpros) > 63 THEN
        RAISE EXCEPTION 'feature class name % is not allowed', coalesce(quote_literal(p_name), 'NULL')
            USING ERRCODE = 'TG101',
                  DETAIL = 'A class name is also a table name: lower-case letters, digits and underscores, '
                           'starting with a letter, at most 54 characters, not an SQL keyword.';
    END IF;
    -- geotypes and time models are the registered data models' (tgsis.data_models)
    IF v_geotype IS NULL OR NOT EXISTS (SELECT FROM tgsis.data_models m WHERE v_geotype = ANY (m.geotypes)) THEN
        RAISE EXCEPTION 'unknown geotype % for feature class %', coalesce(quote_literal(p_geotype), 'NULL'), p_name
            USING ERRCODE = 'TG100',
                  HINT = tgsis.or_list(ARRAY(SELECT DISTINCT g FROM tgsis.data_models m, unnest(m.geotypes) AS g ORDER BY g));
    END IF;
    IF v_align IS NULL OR v_align NOT IN ('VERTEX', 'CELL') THEN
        RAISE EXCEPTION 'property alignment % of feature class % must be VERTEX or CELL',
                coalesce(quote_literal(p_proalignment), 'NULL'), p_name
            USING ERRCODE = 'TG100';
    END IF;
    SELECT * INTO v_dm FROM tgsis.data_models m WHERE m.timemodel = v_model;
    IF v_model IS NULL OR NOT FOUND THEN
        RAISE EXCEPTION 'time model % of feature class % must be %', coalesce(quote_literal(p_time_model), 'NULL'), p_name,
                        tgsis.or_list(ARRAY(SELECT m.timemodel FROM tgsis.data_models m WHERE m.model > 0 ORDER BY m.model))
            USING ERRCODE = 'TG100',
                  HINT = (SELECT string_agg(format('%s: %s (model %s)', m.timemodel, m.name, m.model), '; ' ORDER BY m.model)
                            FROM tgsis.data_models m WHERE m.model > 0);
    END IF;
    -- a temporal model is one whose class tables have a time key
    v_temporal := jsonb_array_length(v_dm.timekey) > 0;
    -- G-maps: properties belong to the cells of one level (the spec's cell level attach), _idx a cell id
    IF v_dm.cell_levels THEN
        IF p_cell_level IS NULL OR p_cell_level < 0 THEN
            RAISE EXCEPTION 'a % feature class needs the level of the cells its properties belong to, got %', v_model,
                    coalesce(p_cell_level::text, 'NULL')
                USING ERRCODE = 'TG100', HINT = 'p_cell_level => 0 (vertices), 1 (edges), 2 (faces), 3 (volumes), ...';
        END IF;
        v_align := 'CELL';
    ELSIF p_cell_level IS NOT NULL THEN
        RAISE EXCEPTION 'a % feature class attaches properties to vertices or simplices, not to cells of a level', v_model
            USING ERRCODE = 'TG100', HINT = 'leave p_cell_level out, or register a class of G-maps (p_time_model => ''GMAP'')';
    END IF;
    IF NOT v_geotype = ANY (v_dm.geotypes) THEN
        RAISE EXCEPTION 'a % feature class holds % features, not %', v_model, tgsis.or_list(v_dm.geotypes), v_geotype
            USING ERRCODE = 'TG100', HINT = format('time model %s (%s) is for %s', v_model, v_dm.name, tgsis.or_list(v_dm.geotypes));
    END IF;
    IF NOT v_temporal AND (p_time_unit IS NOT NULL OR coalesce(p_instant_properties, '[]') NOT IN ('[]', '{}')) THEN
        RAISE EXCEPTION 'static feature class % takes no time unit or per-instant properties', p_name
            USING ERRCODE = 'TG100',
                  HINT = format('give time_model => %s for a temporal class',
                                tgsis.or_list(ARRAY(SELECT quote_literal(m.timemodel) FROM tgsis.data_models m
                                                     WHERE jsonb_array_length(m.timekey) > 0 ORDER BY m.model)));
    END IF;
    IF v_temporal THEN
        v_pros := p_name || '_pros';
        SELECT string_agg(format('%I double precision NOT NULL, ', k ->> 'name'), '' ORDER BY i) INTO v_timekey
          FROM jsonb_array_elements(v_dm.timekey) WITH ORDINALITY AS e (k, i);
    END IF;
    IF p_srs IS NULL OR p_srs < 0 THEN
        RAISE EXCEPTION 'SRS % of feature class % must be an id >= 0 (0: undefined)', p_srs, p_name USING ERRCODE = 'TG100';
    END IF;
    -- tgsis's own schema would make tgsis's catalog tables and the class's look alike
    -- (enable_feature_versioning would then refuse to version them, for everyone)
    IF p_schema = ANY (ARRAY['tgsis', 'information_schema']) OR p_schema LIKE 'pg\_%' THEN
        RAISE EXCEPTION 'feature classes may not go into schema %', quote_literal(p_schema)
            USING ERRCODE = 'TG101', DETAIL = 'It is tgsis''s own schema or a system schema.',
                  HINT = 'choose a schema of your own, or leave the schema at its default (public)';
    END IF;
    IF p_schema IS NULL OR to_regnamespace(quote_ident(p_schema)) IS NULL THEN
        RAISE EXCEPTION 'schema % does not exist', coalesce(quote_literal(p_schema), 'NULL')
            USING ERRCODE = 'TG200', HINT = 'create it first, or leave the schema at its default (public)';
    END IF;
    -- a schema's owner may drop any table in it and put its own in its place,
    -- which tgsis's definer code would then act on as tgsis's owner
    SELECT CASE WHEN n.nspowner = 'pg_database_owner'::regrole THEN d.datdba ELSE n.nspowner END INTO v_nspowner
      FROM pg_namespace n, pg_database d WHERE n.nspname = p_schema AND d.datname = current_database();
    IF v_nspowner <> (SELECT relowner FROM pg_class WHERE oid = 'tgsis.catalog'::regclass)
       AND NOT (SELECT rolsuper FROM pg_roles WHERE oid = v_nspowner) THEN
        RAISE EXCEPTION 'schema % belongs to %, who could replace the tables of a feature class there', p_schema,
                pg_get_userbyid(v_nspowner)
            USING ERRCODE = 'TG002',
                  DETAIL = 'Feature classes go into schemas owned by tgsis''s owner or by a superuser.',
                  HINT = format('a superuser may run: ALTER SCHEMA %I OWNER TO %I', p_schema, current_user);
    END IF;
    IF NOT has_schema_privilege(v_caller, p_schema, 'CREATE') THEN
        RAISE EXCEPTION 'role % may not create tables in schema %', v_caller, p_schema
            USING ERRCODE = 'TG002', HINT = format('the schema''s owner may run: GRANT CREATE ON SCHEMA %I TO %I', p_schema, v_caller);
    END IF;
    IF NOT has_schema_privilege(current_user, p_schema, 'CREATE') THEN  -- tgsis's owner creates the tables
        RAISE EXCEPTION 'tgsis''s owner % may not create tables in schema %', current_user, p_schema
            USING ERRCODE = 'TG002', DETAIL = 'The tables of a feature class belong to tgsis''s owner.',
                  HINT = format('the schema''s owner may run: GRANT CREATE ON SCHEMA %I TO %I', p_schema, current_user);
    END IF;
    IF EXISTS (SELECT FROM tgsis.catalog WHERE classname = p_name) THEN
        RAISE EXCEPTION 'feature class % exists already', p_name
            USING ERRCODE = 'TG201', HINT = 'tgsis.drop_feature_class removes it';
    END IF;
    IF to_regclass(format('%I.%I', p_schema, p_name)) IS NOT NULL
       OR to_regclass(format('%I.%I', p_schema, v_cellpros)) IS NOT NULL
       OR to_regclass(format('%I.%I', p_schema, v_view)) IS NOT NULL
       OR to_regclass(format('%I.%I', p_schema, coalesce(v_pros, v_cellpros))) IS NOT NULL THEN
        RAISE EXCEPTION 'a table or view named %, %, % or % exists already in schema %',
                p_name, v_cellpros, v_view, coalesce(v_pros, p_name || '_pros'), p_schema
            USING ERRCODE = 'TG201';
    END IF;

    SELECT coalesce(string_agg(format(', %I %s', name, typename), '' ORDER BY ord), ''),
           coalesce(jsonb_agg(jsonb_build_object('name', name, 'type', typename) ORDER BY ord), '[]')
      INTO v_fcols, v_fprops
      FROM tgsis.property_columns(p_feature_properties, false, 'feature');
    v_notnull := CASE WHEN v_geotype = 'GEOMETRYCOLLECTION' THEN '' ELSE ' NOT NULL' END;
    -- a vector property (size k > 1) is one column holding an array of exactly k values; a
    -- property aligned otherwise than the class (alignment is per property) goes to v_other
    WITH props AS (
        SELECT p.name, p.ord, p.size, nullif(p.alignment, v_align) AS alignment,
               -- a collection's members may each have some of the class's properties: the rows of a
               -- member hold NULL in the columns of properties it lacks
               CASE WHEN p.size = 1 THEN format(', %I %s%s', p.name, p.typename, v_notnull)
                    ELSE format(', %I %s[]%s CHECK (array_ndims(%I) = 1 AND array_lower(%I, 1) = 1 '
                                'AND cardinality(%I) = %s AND array_position(%I, NULL) IS NULL)',
                                p.name, p.typename, v_notnull, p.name, p.name, p.name, p.size, p.name) END AS definition,
               jsonb_build_object('name', p.name, 'type', p.typename) AS item
          FROM tgsis.property_columns(p_cell_properties, true, lower(v_align)) p)
    SELECT coalesce(string_agg(definition, '' ORDER BY ord) FILTER (WHERE alignment IS NULL), ''),
           string_agg(definition, '' ORDER BY ord) FILTER (WHERE alignment IS NOT NULL),
           coalesce(jsonb_agg(item || CASE WHEN size > 1 THEN jsonb_build_object('size', size) ELSE '{}' END
                                   || CASE WHEN alignment IS NOT NULL THEN jsonb_build_object('alignment', alignment)
                                           ELSE '{}' END ORDER BY ord), '[]')
      INTO v_ccols, v_ocols, v_cprops
      FROM props;
    IF v_temporal AND EXISTS (SELECT FROM jsonb_array_elements(v_cprops) p WHERE p ? 'size' OR p ? 'alignment') THEN
        RAISE EXCEPTION 'temporal feature class % takes no vector properties nor properties of another alignment', p_name
            USING ERRCODE = 'TG103', HINT = 'give one scalar property per component, all of the class''s alignment';
    END IF;
    IF v_ocols IS NOT NULL THEN
        v_other := p_name || CASE v_align WHEN 'VERTEX' THEN '_simplexpros' ELSE '_vertexpros' END;
        IF length(v_other) > 63 THEN
            RAISE EXCEPTION 'feature class name % is too long for a class with vertex and cell properties', p_name
                USING ERRCODE = 'TG101', DETAIL = format('Its table %s would have more than 63 characters.', v_other);
        END IF;
        IF to_regclass(format('%I.%I', p_schema, v_other)) IS NOT NULL THEN
            RAISE EXCEPTION 'a table or view named % exists already in schema %', v_other, p_schema USING ERRCODE = 'TG201';
        END IF;
    END IF;
    SELECT coalesce(string_agg(format(', %I %s', name, typename), '' ORDER BY ord), ''),
           coalesce(jsonb_agg(jsonb_build_object('name', name, 'type', typename) ORDER BY ord), '[]')
      INTO v_icols, v_iprops
      FROM tgsis.property_columns(p_instant_properties, false, 'per-instant');

    IF EXISTS (SELECT FROM tgsis.versioned_tables WHERE schemaname = 'tgsis' AND tablename = 'geometry') THEN
        -- model 1 is versioned: the key to tgsis.geometry cannot hold across
        -- versions; record it as versioning would have dropped it
        EXECUTE format('CREATE TABLE %I.%I (_geoid bigint PRIMARY KEY%s)', p_schema, p_name, v_fcols);
        INSERT INTO tgsis.versioning_dropped (schemaname, tablename, name, definition, refschema, reftable, dropped_for)
        VALUES (p_schema, p_name, p_name || '__geoid_fkey',
                'FOREIGN KEY (_geoid) REFERENCES tgsis.geometry(geoid) ON DELETE CASCADE', 'tgsis', 'geometry',
                format('%I.%I', p_schema, p_name));
    ELSE
        EXECUTE format('CREATE TABLE %I.%I (_geoid bigint PRIMARY KEY REFERENCES tgsis.geometry (geoid) ON DELETE CASCADE%s)',
                       p_schema, p_name, v_fcols);
    END IF;
    -- no foreign key to the feature table: a per-row check would dominate bulk uploads
    EXECUTE format('CREATE TABLE %I.%I (_geoid bigint NOT NULL, %s_idx bigint NOT NULL%s, PRIMARY KEY (_geoid, %s_idx))',
                   p_schema, v_cellpros, coalesce(v_timekey, ''), v_ccols, tgsis.time_key_columns(v_model));
    IF v_pros IS NOT NULL THEN
        EXECUTE format('CREATE TABLE %I.%I (_geoid bigint NOT NULL, %s%s, PRIMARY KEY (_geoid, %s))',
                       p_schema, v_pros, rtrim(v_timekey, ', '), v_icols, rtrim(tgsis.time_key_columns(v_model), ', '));
        EXECUTE format('COMMENT ON TABLE %I.%I IS %L', p_schema, v_pros,
                       format('tgsis feature class %s: per-instant feature properties (%s)', p_name,
                              format('one row per feature and %s', rtrim(tgsis.time_key_columns(v_model), ', '))));
        EXECUTE format('COMMENT ON COLUMN %I.%I._geoid IS %L', p_schema, v_pros, 'the feature (_geoid of ' || p_name || ')');
        PERFORM tgsis.comment_time_key_columns(p_schema, v_pros, v_model);
        PERFORM tgsis.comment_property_columns(p_schema, v_pros, v_iprops, 'per-instant feature property');
        EXECUTE format('GRANT SELECT ON %I.%I TO tgsis_reader', p_schema, v_pros);
        EXECUTE format('GRANT INSERT, UPDATE, DELETE ON %I.%I TO tgsis_editor', p_schema, v_pros);
        PERFORM tgsis.comment_time_key_columns(p_schema, v_cellpros, v_model);
    END IF;

    EXECUTE format('COMMENT ON TABLE %I.%I IS %L', p_schema, p_name,
                   format('tgsis feature class %s: one row per %s feature (_geoid = tgsis.geometry.geoid)', p_name, v_geotype));
    EXECUTE format('COMMENT ON COLUMN %I.%I._geoid IS %L', p_schema, p_name, 'the feature''s geometry (tgsis.geometry.geoid)');
    -- a collection's properties belong to its members: _geoid is a member geometry, not the feature
    EXECUTE format('COMMENT ON TABLE %I.%I IS %L', p_schema, v_cellpros,
                   format('tgsis feature class %s: %s properties (%s_idx = %s)', p_name, lower(v_align),
                          CASE WHEN v_geotype = 'GEOMETRYCOLLECTION' THEN '_geoid = member geometry, ' ELSE '' END,
                          CASE WHEN v_dm.cell_levels THEN format('abstract cell id of a %s-cell', p_cell_level)
                               WHEN v_align = 'VERTEX' THEN 'tgsis.vrtx.vrtxid'
                               WHEN v_geotype = 'GEOMETRYCOLLECTION' THEN 'simplex id in the member''s point/segment/trgl/tetra'
                               ELSE format('tgsis.%s id', tgsis.simplex_table(v_geotype)) END));
    EXECUTE format('COMMENT ON COLUMN %I.%I._geoid IS %L', p_schema, v_cellpros,
                   CASE WHEN v_geotype = 'GEOMETRYCOLLECTION'
                        THEN 'a member geometry (tgsis.geometry.geoid) of a feature of ' || p_name
                        ELSE 'the feature (_geoid of ' || p_name || ')' END);
    EXECUTE format('COMMENT ON COLUMN %I.%I._idx IS %L', p_schema, v_cellpros,
                   CASE WHEN v_dm.cell_levels THEN format('abstract cell id (acellid) of a %s-cell', p_cell_level)
                        WHEN v_align = 'VERTEX' THEN 'vertex id (vrtxid)' ELSE 'simplex id' END);
    PERFORM tgsis.comment_property_columns(p_schema, p_name, v_fprops, 'per-feature property');
    PERFORM tgsis.comment_property_columns(p_schema, v_cellpros,
                                           (SELECT coalesce(jsonb_agg(p), '[]') FROM jsonb_array_elements(v_cprops) p
                                             WHERE NOT p ? 'alignment'),
                                           format('%s property', lower(v_align)));

    IF v_other IS NOT NULL THEN  -- the properties of the other alignment: the same keys, _idx of the other kind
        EXECUTE format('CREATE TABLE %I.%I (_geoid bigint NOT NULL, _idx bigint NOT NULL%s, PRIMARY KEY (_geoid, _idx))',
                       p_schema, v_other, v_ocols);
        EXECUTE format('COMMENT ON TABLE %I.%I IS %L', p_schema, v_other,
                       format('tgsis feature class %s: %s properties (%s_idx = %s)', p_name,
                              CASE v_align WHEN 'VERTEX' THEN 'cell' ELSE 'vertex' END,
                              CASE WHEN v_geotype = 'GEOMETRYCOLLECTION' THEN '_geoid = member geometry, ' ELSE '' END,
                              CASE WHEN v_align = 'CELL' THEN 'tgsis.vrtx.vrtxid'
                                   WHEN v_geotype = 'GEOMETRYCOLLECTION' THEN 'simplex id in the member''s point/segment/trgl/tetra'
                                   ELSE format('tgsis.%s id', tgsis.simplex_table(v_geotype)) END));
        EXECUTE format('COMMENT ON COLUMN %I.%I._geoid IS %L', p_schema, v_other,
                       CASE WHEN v_geotype = 'GEOMETRYCOLLECTION'
                            THEN 'a member geometry (tgsis.geometry.geoid) of a feature of ' || p_name
                            ELSE 'the feature (_geoid of ' || p_name || ')' END);
        EXECUTE format('COMMENT ON COLUMN %I.%I._idx IS %L', p_schema, v_other,
                       CASE v_align WHEN 'CELL' THEN 'vertex id (vrtxid)' ELSE 'simplex id' END);
        PERFORM tgsis.comment_property_columns(p_schema, v_other,
                                               (SELECT jsonb_agg(p) FROM jsonb_array_elements(v_cprops) p WHERE p ? 'alignment'),
                                               CASE v_align WHEN 'VERTEX' THEN 'cell property' ELSE 'vertex property' END);
        EXECUTE format('GRANT SELECT ON %I.%I TO tgsis_reader', p_schema, v_other);
        EXECUTE format('GRANT INSERT, UPDATE, DELETE ON %I.%I TO tgsis_editor', p_schema, v_other);
    END IF;
    EXECUTE format('GRANT SELECT ON %I.%I, %I.%I TO tgsis_reader', p_schema, p_name, p_schema, v_cellpros);
    EXECUTE format('GRANT INSERT, UPDATE, DELETE ON %I.%I, %I.%I TO tgsis_editor', p_schema, p_name, p_schema, v_cellpros);

    INSERT INTO tgsis.catalog (classname, schemaname, geotype, featuretable, cellprotable, otherprotable, viewname,
                               protablename, timemodel, timeunit, proalignment, srs, feature_properties, cell_properties,
                               instant_properties, description, created_by, celllevel, versioned)
    VALUES (p_name, p_schema, v_geotype, p_name, v_cellpros, v_other, v_view, v_pros, v_model, p_time_unit, v_align, p_srs,
            v_fprops, v_cprops, v_iprops, p_description, v_caller, p_cell_level, coalesce(p_versioned, true))
    RETURNING * INTO v_row;
    -- the property tables of a STATIC class go to chunks when model 1 is in chunks and tgsis.storage does not say
    -- rows (tgsis.chunk_class_by_default): empty, so nothing to convert; before versioning, which versions a class
    -- in chunks as it is, and before the class view
    PERFORM tgsis.chunk_class_by_default(p_name);
    -- once model 1 is versioned, every new class is versioned with it, unless registered without versioning
    IF v_row.versioned AND EXISTS (SELECT FROM tgsis.versioned_tables WHERE schemaname = 'tgsis' AND tablename = 'geometry') THEN
        PERFORM tgsis.version_class_tables(p_name);
    END IF;
    PERFORM tgsis.create_class_view(p_name);
    RETURN v_row;
END
$$;

COMMENT ON FUNCTION tgsis.register_feature_class(text, text, jsonb, jsonb, text, integer, text, text, text, jsonb, text, integer, boolean) IS
    'register a feature class (tgsis_admin members with CREATE on the schema; the tables belong to tgsis''s owner): creates <schema>.<name> (features), <name>_cellpros (vertex/cell properties of the class''s alignment), <name>_simplexpros or <name>_vertexpros (properties of the other alignment, if any), <name>_v (view) and for temporal classes (INSTANTS, EVOLVING) <name>_pros (per-instant properties); a STATIC class''s property tables in chunks when model 1 is in chunks and tgsis.storage is not rows (tgsis.chunk_class_by_default); records it in tgsis.catalog; versioned with every class when feature versioning is on, unless p_versioned => false (its features are then of no version: one state every version sees, written in DEFAULT)';
