-- tgsis.insert_postgis_feature(class, geom, properties, name): store a PostGIS geometry as a new feature of a static class; returns its id.
-- Why in SQL: a psql or QGIS user holding PostGIS geometries (an imported
-- TIN, a digitised fault trace) stores them without a client. The geometry
-- is read by tgsis.mesh_from_postgis; the rows go in with plain INSERTs
-- through the names a psql user writes (under feature versioning: the
-- versioned views, in the session's version), then tgsis.refresh_geometry
-- sets the box and counts, in the caller's transaction: an error leaves
-- nothing behind. It runs as the caller (an editor writes features). Only
-- static classes without vertex or cell properties: the geometry carries
-- none, and a temporal class needs its instants (use Python's insert_feature).
-- Model 1 stored in chunks (tgsis.stored_in_chunks): the new object's
-- vertices and cells go in with one call per table of tgsis.write_object_rows
-- (the bulk writer of chunks with the row path's checks: the face's INSERT
-- privilege, the class's write right, the version's, the revision, the note of
-- the changed object), not row by row through the face, whose INSTEAD OF
-- trigger rewrites a chunk per row.
CREATE FUNCTION tgsis.insert_postgis_feature(p_class text, p_geom anyelement, p_properties jsonb DEFAULT '{}',
                                             p_name text DEFAULT NULL)
RETURNS bigint
LANGUAGE plpgsql
VOLATILE
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_class tgsis.catalog := tgsis.catalog_row(p_class);
    v_mesh  record;
    v_geoid bigint;
    v_extra text[];
    v_bad   bigint;
    v_table text;
BEGIN
    IF v_class.timemodel <> 'STATIC' THEN
        RAISE EXCEPTION 'feature class % is %: its features have instants, which a PostGIS geometry does not give', p_class,
                v_class.timemodel
            USING ERRCODE = 'TG100', HINT = 'store temporal features from Python (tgsis.insert_feature) or a static class';
    END IF;
    IF jsonb_array_length(v_class.cell_properties) > 0 THEN
        RAISE EXCEPTION 'feature class % has vertex or cell properties, which a PostGIS geometry does not carry', p_class
            USING ERRCODE = 'TG103', HINT = 'store the feature from Python (tgsis.insert_feature) with its properties';
    END IF;
    IF p_properties IS NULL OR jsonb_typeof(p_properties) <> 'object' THEN
        RAISE EXCEPTION 'the feature properties must be a JSON object, not %', coalesce(jsonb_typeof(p_properties), 'NULL')
            USING ERRCODE = 'TG100', HINT = 'e.g. ''{"name": "F1"}''';
    END IF;
    SELECT array_agg(k ORDER BY k) INTO v_extra
      FROM jsonb_object_keys(p_properties) k
     WHERE NOT EXISTS (SELECT FROM jsonb_array_elements(v_class.feature_properties) f WHERE f->>'name' = k);
    IF v_extra IS NOT NULL THEN
        RAISE EXCEPTION 'feature class % has no feature properties %', p_class, array_to_string(v_extra, ', ')
            USING ERRCODE = 'TG103',
                  HINT = format('its properties: %s',
                                coalesce((SELECT string_agg(f->>'name', ', ') FROM jsonb_array_elements(v_class.feature_properties) f),
                                         'none'));
    END IF;
    SELECT * INTO v_mesh FROM tgsis.mesh_from_postgis(p_geom);
    IF v_mesh.geotype <> v_class.geotype THEN
        RAISE EXCEPTION 'feature class % holds % features; the geometry is a %', p_class, v_class.geotype, v_mesh.geotype
            USING ERRCODE = 'TG100',
                  HINT = 'SURFACE: TIN, POLYHEDRALSURFACE, (MULTI)POLYGON; MULTILINESTRING: (MULTI)LINESTRING; MULTIPOINT: (MULTI)POINT';
    END IF;
    SELECT c INTO v_bad FROM generate_subscripts(v_mesh.cells, 1) c
     WHERE (SELECT count(DISTINCT v) FROM unnest(v_mesh.cells[c:c]) v) < array_length(v_mesh.cells, 2)
     LIMIT 1;
    IF v_bad IS NOT NULL THEN
        RAISE EXCEPTION 'cell % of the geometry repeats a vertex (a degenerate face or a zero-length segment)', v_bad - 1
            USING ERRCODE = 'TG102', HINT = 'ST_RemoveRepeatedPoints(geom) removes repeated points';
    END IF;

    v_geoid := tgsis.new_geometry(v_class.geotype, p_name, NULL, 0, 0, p_class => v_class.classname);
    v_table := tgsis.simplex_table(v_class.geotype);
    IF tgsis.stored_in_chunks('vrtx') AND tgsis.stored_in_chunks(v_table) THEN
        -- the tables' columns as rows of (columns x ids) arrays: the mesh's (ids x columns) transposed
        PERFORM tgsis.write_object_rows(
                    'vrtx', v_geoid, '{}', ARRAY(SELECT i - 1 FROM generate_subscripts(v_mesh.vertices, 1) i ORDER BY i),
                    (SELECT array_agg(c.a ORDER BY c.j)
                       FROM (SELECT j, array_agg(v_mesh.vertices[i][j] ORDER BY i) AS a
                               FROM generate_subscripts(v_mesh.vertices, 1) i, generate_subscripts(v_mesh.vertices, 2) j
                              GROUP BY j) c))
          WHERE array_length(v_mesh.vertices, 1) > 0;
        PERFORM tgsis.write_object_rows(
                    v_table, v_geoid, '{}', ARRAY(SELECT i - 1 FROM generate_subscripts(v_mesh.cells, 1) i ORDER BY i), NULL,
                    (SELECT array_agg(c.a ORDER BY c.j)
                       FROM (SELECT j, array_agg(v_mesh.cells[i][j] ORDER BY i) AS a
                               FROM generate_subscripts(v_mesh.cells, 1) i, generate_subscripts(v_mesh.cells, 2) j
                              GROUP BY j) c))
          WHERE array_length(v_mesh.cells, 1) > 0;
    ELSE
        INSERT INTO tgsis.vrtx (geoid, vrtxid, x, y, z)
        SELECT v_geoid, i - 1, v_mesh.vertices[i][1], v_mesh.vertices[i][2], v_mesh.vertices[i][3]
          FROM generate_subscripts(v_mesh.vertices, 1) i;
        CASE v_class.geotype
        WHEN 'SURFACE' THEN
            INSERT INTO tgsis.trgl (geoid, trglid, vrtxid1, vrtxid2, vrtxid3)
            SELECT v_geoid, i - 1, v_mesh.cells[i][1], v_mesh.cells[i][2], v_mesh.cells[i][3]
              FROM generate_subscripts(v_mesh.cells, 1) i;
        WHEN 'MULTILINESTRING' THEN
            INSERT INTO tgsis.segment (geoid, segid, vrtxid1, vrtxid2)
            SELECT v_geoid, i - 1, v_mesh.cells[i][1], v_mesh.cells[i][2] FROM generate_subscripts(v_mesh.cells, 1) i;
        ELSE
            INSERT INTO tgsis.point (geoid, pointid, vrtxid1)
            SELECT v_geoid, i - 1, v_mesh.cells[i][1] FROM generate_subscripts(v_mesh.cells, 1) i;
        END CASE;
    END IF;
    PERFORM tgsis.refresh_geometry(v_geoid);
    EXECUTE format('INSERT INTO %I.%I SELECT * FROM jsonb_populate_record(NULL::%I.%I, $1)',
                   v_class.schemaname, v_class.featuretable, v_class.schemaname, v_class.featuretable)
      USING p_properties || jsonb_build_object('_geoid', v_geoid);
    RETURN v_geoid;
END
$$;

COMMENT ON FUNCTION tgsis.insert_postgis_feature(text, anyelement, jsonb, text) IS
    'store a PostGIS geometry with Z (TIN, POLYHEDRALSURFACE, polygons, lines, points: see tgsis.mesh_from_postgis) as a new feature of a static class without vertex or cell properties, with the given feature properties and name; returns its id';
