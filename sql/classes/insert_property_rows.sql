-- tgsis.insert_property_rows(class, table, geoids, columns, values): give geometries without property rows one row per vertex or cell, in every version.
-- The rows are made from the geometries' own rows in the model's storage:
-- one per vertex (tgsis.vrtx) for a table of vertex properties, one per
-- simplex (tgsis.point, segment, trgl, tetra) for one of cell properties.
-- When the class is versioned, each row copies the revision and lastrevs of
-- the vertex or simplex row version it stands for, so that every version and
-- every revision sees a property row exactly where it sees the vertex or
-- cell (a vertex moved in a child version has a row version per position,
-- so has its property; a table stored in chunks gives the rows of every
-- chunk version, tgsis.<table>_chunk_rows, so a property row per slot and
-- chunk version); the storage's statement trigger notes the objects
-- in tgsis.revision_objects, as for any direct write. A class registered
-- without versioning keeps plain tables while the model's are versioned:
-- its features are written in DEFAULT only, whose live rows (not closed)
-- are their one state, and those are what its rows stand for. p_columns get the SQL
-- expressions p_values (literals made by the caller with %L and a cast);
-- the other columns their defaults. Only models whose vertex and cell
-- properties are keyed by vertex or simplex id alone (no time key, no cell
-- levels: static objects) are handled; others are refused (TG103), nothing
-- written. A table stored in chunks (tgsis.store_class_in_chunks) gets its
-- rows through its face (each touched chunk written once, at the statement's
-- end) when the class is unversioned; versioned, it is refused by name
-- (TG103: no writer of chunks makes the chunk versions of every revision;
-- the HINT says to go by rows). The face is written as from DEFAULT's
-- working revision whatever the session's version or viewed revision
-- (settings tgsis.version and tgsis.revision cleared for that INSERT and
-- put back after it): the rows made are the table's one state, which every
-- version reads, as the rows path's direct INSERT into the plain table
-- writes them from any version (the face would refuse TG305). Unversioned,
-- another role's exclusive lock on a feature (in DEFAULT) refuses the rows
-- on both storages alike (TG303, tgsis.check_objects_unlocked), as the face
-- refuses them. Returns the geometries and the rows
-- (vertices or cells, not row versions) given. Runs as its callers (tgsis's
-- owner).
CREATE FUNCTION tgsis.insert_property_rows(p_class tgsis.catalog, p_table text, p_geoids bigint[], p_columns text[],
                                           p_values text[], OUT features bigint, OUT rows bigint)
LANGUAGE plpgsql
VOLATILE
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_dm       tgsis.data_models;
    v_align    text := CASE WHEN p_table = p_class.cellprotable THEN p_class.proalignment
                            WHEN p_class.proalignment = 'VERTEX' THEN 'CELL' ELSE 'VERTEX' END;
    v_versioned boolean := EXISTS (SELECT FROM tgsis.versioned_tables t
                                    WHERE t.schemaname = p_class.schemaname AND t.tablename = p_table);
    v_chunked  boolean := tgsis.stored_in_chunks(p_class.schemaname, p_table);
    v_sources  text[];
    v_source   text;
    v_selects  text[] := '{}';
    v_source_versioned boolean;
    v_version  text;
    v_viewing  text;
BEGIN
    features := 0;
    rows := 0;
    IF cardinality(p_geoids) = 0 THEN
        RETURN;
    END IF;
    SELECT * INTO v_dm FROM tgsis.data_models d WHERE d.timemodel = p_class.timemodel;
    IF NOT FOUND OR v_dm.timekey <> '[]' OR v_dm.cell_levels THEN
        RAISE EXCEPTION 'feature class % has % stored geometries without rows in %, and tgsis cannot make them for model %',
                p_class.classname, cardinality(p_geoids), p_table, coalesce(v_dm.model::text || ' (' || v_dm.name || ')',
                                                                           quote_literal(p_class.timemodel))
            USING ERRCODE = 'TG103',
                  DETAIL = 'Its vertex or cell property rows are keyed by time or by cell level as well; a class registered without such properties stores none.',
                  HINT = 'register a new class with the property and copy the features into it';
    END IF;
    IF v_chunked AND v_versioned THEN
        -- the rows of every version would be chunk versions of every revision, which no writer of chunks makes
        -- (the face and tgsis.write_property_rows write the working revision)
        RAISE EXCEPTION 'feature class % has % stored geometries without rows in %, which is versioned and stored in chunks',
                p_class.classname, cardinality(p_geoids), p_table
            USING ERRCODE = 'TG103',
                  DETAIL = 'Rows made for every version are written into row versions; a versioned table in chunks has none.',
                  HINT = format('store the class as rows, make the rows, then store it in chunks again (in psql: '
                                'SELECT tgsis.store_class_in_rows(%L), then tgsis.store_class_in_chunks(%L))',
                                p_class.classname, p_class.classname);
    END IF;
    v_sources := CASE WHEN v_align = 'VERTEX' THEN ARRAY['vrtx']
                      WHEN p_class.geotype = 'GEOMETRYCOLLECTION' THEN ARRAY['point', 'segment', 'trgl', 'tetra']
                      ELSE ARRAY[tgsis.simplex_table(p_class.geotype)] END;
    FOREACH v_source IN ARRAY v_sources LOOP
        IF NOT EXISTS (SELECT FROM tgsis.model_tables m WHERE m.tablename = v_source AND m.model = v_dm.model) THEN
            RAISE EXCEPTION 'model % has no table tgsis.%', v_dm.model, v_source USING ERRCODE = 'TG103';
        END IF;
        v_source_versioned := EXISTS (SELECT FROM tgsis.versioned_tables t WHERE t.schemaname = 'tgsis' AND t.tablename = v_source);
        IF v_versioned AND NOT v_source_versioned THEN
            RAISE EXCEPTION 'table %.% is versioned and tgsis.% is not', p_class.schemaname, p_table, v_source
                USING ERRCODE = 'TG103', HINT = 'SELECT tgsis.enable_feature_versioning() versions them all';
        END IF;
        v_selects := v_selects || format('SELECT s.geoid, s.%I%s FROM %s s WHERE s.geoid = ANY($1)%s',
                                         CASE v_source WHEN 'vrtx' THEN 'vrtxid' WHEN 'point' THEN 'pointid'
                                                       WHEN 'segment' THEN 'segid' WHEN 'trgl' THEN 'trglid'
                                                       ELSE 'tetraid' END,
                                         CASE WHEN v_versioned THEN ', s.revision, s.lastrevs' ELSE '' END,
                                         -- stored in chunks: every chunk version's rows, each with its
                                         -- revision and lastrevs (the decoded view, no visibility filter)
                                         tgsis.storage_row_versions('tgsis', v_source),
                                         CASE WHEN v_source_versioned AND NOT v_versioned THEN ' AND NOT s.revclosed' ELSE '' END);
    END LOOP;
    IF NOT v_versioned AND EXISTS (SELECT FROM tgsis.object_locks l
                                    WHERE l.objectclass = 'feature' AND l.objectkey = ANY (p_geoids::text[])) THEN
        -- another role's exclusive lock in DEFAULT (the only version that can lock a feature of a class without
        -- versioning) stops these rows on both storages alike: the face checks it (tgsis.chunk_face_write), and the
        -- rows path wrote past it (tests/test_chunk_review5.py); refused naming the objects (TG303), nothing written
        PERFORM tgsis.check_objects_unlocked('feature', p_geoids::text[], tgsis.version_id('DEFAULT'));
    END IF;
    IF v_chunked THEN
        -- the face checks the session's version (TG305 outside DEFAULT's working revision), the rows path does not:
        -- write as DEFAULT's working revision, whose one state every version reads, and put the settings back
        v_version := current_setting('tgsis.version', true);
        v_viewing := current_setting('tgsis.revision', true);
        PERFORM set_config('tgsis.version', '', true), set_config('tgsis.revision', '', true);
    END IF;
    EXECUTE format('WITH made AS (INSERT INTO %s (_geoid, _idx%s%s) SELECT r.* %s FROM (%s) AS r RETURNING _geoid, _idx)
                    SELECT count(DISTINCT _geoid), count(DISTINCT (_geoid, _idx)) FROM made',
                   -- in chunks (unversioned): through the face, whose trigger writes each touched chunk once
                   CASE WHEN v_chunked THEN format('%I.%I', p_class.schemaname, p_table)
                        ELSE tgsis.storage_table(p_class.schemaname, p_table) END,
                   CASE WHEN v_versioned THEN ', revision, lastrevs' ELSE '' END,
                   (SELECT string_agg(format(', %I', c), '') FROM unnest(p_columns) AS c),
                   (SELECT string_agg(', ' || v, '') FROM unnest(p_values) AS v),
                   array_to_string(v_selects, ' UNION ALL '))
       INTO features, rows USING p_geoids;
    IF v_chunked THEN
        PERFORM set_config('tgsis.version', coalesce(v_version, ''), true),
                set_config('tgsis.revision', coalesce(v_viewing, ''), true);
    END IF;
END
$$;

COMMENT ON FUNCTION tgsis.insert_property_rows(tgsis.catalog, text, bigint[], text[], text[]) IS
    'insert one row per vertex or cell of the given geometries into a vertex or cell property table of a static class (copying the revision and lastrevs of each vertex or simplex row version when versioned), the columns given set to the SQL expressions given (a table stored in chunks through its face when unversioned, written as from DEFAULT''s working revision whatever the session''s version, as the rows path writes); returns the geometries and rows given; TG103 for models keyed by time or cell level, and for a versioned table stored in chunks';
