-- tgsis.drop_property(class, name, kind, force): remove a property of a feature class, in every version.
-- Its column goes from its table (from the storage <table>_ver when
-- versioned: every version loses it, table definitions are not versioned)
-- and from tgsis.catalog. While any row of any version holds a value of it
-- (not NULL), dropping would lose data: refused (TG202) unless p_force (the
-- count: distinct key and value over every version, rows and chunks alike). Key
-- and time columns are no properties and are refused (TG101). The last
-- property column of a table in chunks takes the class back to rows for the
-- drop (a chunk would hold nothing), the tables keeping properties back to
-- chunks after it. Runs as
-- tgsis's owner (SECURITY DEFINER), for members of tgsis_admin.
CREATE FUNCTION tgsis.drop_property(p_class text, p_name text, p_kind text DEFAULT NULL, p_force boolean DEFAULT false)
RETURNS tgsis.catalog
LANGUAGE plpgsql
VOLATILE
SECURITY DEFINER
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_class  tgsis.catalog := tgsis.class_for_change(p_class, 'drop');
    v_prop   record;
    v_list   text;
    v_values bigint;
    v_row    tgsis.catalog;
    v_rechunk boolean := false;  -- the class was moved to rows to drop its table's last property in chunks
    v_detail text;
BEGIN
    SELECT * INTO v_prop FROM tgsis.class_property(v_class, p_name, p_kind);
    -- the values held, one per key and value over every version, the same on rows and on chunks (whose chunk
    -- versions repeat the slots they did not change: decoded, tgsis.storage_row_versions)
    EXECUTE format('SELECT count(*) FROM (SELECT DISTINCT _geoid, %s%I FROM %s r WHERE %I IS NOT NULL) v',
                   CASE v_prop.kind WHEN 'feature' THEN ''
                                    WHEN 'cell' THEN tgsis.time_key_columns(v_class.timemodel) || '_idx, '
                                    ELSE tgsis.time_key_columns(v_class.timemodel) END,
                   p_name, tgsis.storage_row_versions(v_class.schemaname, v_prop.tablename), p_name)
       INTO v_values;
    IF v_values > 0 AND NOT coalesce(p_force, false) THEN
        RAISE EXCEPTION '% property % of feature class % holds % value(s)', v_prop.kind, quote_literal(p_name), p_class, v_values
            USING ERRCODE = 'TG202',
                  DETAIL = format('Rows of %s in every version count; dropping the property deletes its values.', v_prop.tablename),
                  HINT = 'drop it with p_force => true to delete its values';
    END IF;
    -- the last property column of a table in chunks: a chunk would hold nothing (tgsis.chunk_columns refuses it), so
    -- the class goes back to rows first (tgsis.store_class_in_rows, verified), the column is dropped from the rows,
    -- and a table of the class that keeps properties goes back to chunks (docs/storage.md, "Property chunks by
    -- default: the rule": a table without a property column is rows); to_regclass, not a cast: an IF's AND is not
    -- evaluated in order, and the shape of a rows table does not exist
    IF v_prop.kind = 'cell' AND tgsis.stored_in_chunks(v_class.schemaname, v_prop.tablename)
       AND NOT EXISTS (SELECT FROM pg_attribute a
                        WHERE a.attrelid = to_regclass(tgsis.chunk_relation(format('%I.%I', v_class.schemaname, v_prop.tablename), '_shape'))
                          AND a.attnum > 0 AND NOT a.attisdropped AND a.attname <> p_name
                          AND a.attname NOT IN ('_geoid', '_idx', '_times', '_timem', '_timet')) THEN
        BEGIN
            PERFORM tgsis.store_class_in_rows(p_class);
        EXCEPTION WHEN dependent_objects_still_exist THEN  -- a user's view over the face: refused as on rows
            GET STACKED DIAGNOSTICS v_detail = PG_EXCEPTION_DETAIL;
            RAISE EXCEPTION 'other objects depend on table %.% of feature class %', v_class.schemaname, v_prop.tablename, p_class
                USING ERRCODE = 'TG202', DETAIL = v_detail,
                      HINT = 'drop the views that read the class''s tables, change the class, then create them again';
        END;
        v_rechunk := true;
    END IF;
    PERFORM tgsis.alter_class_table(v_class, v_prop.tablename, ARRAY[format('DROP COLUMN %I', p_name)]);
    v_list := CASE v_prop.kind WHEN 'feature' THEN 'feature_properties' WHEN 'cell' THEN 'cell_properties'
                               ELSE 'instant_properties' END;
    EXECUTE format('UPDATE tgsis.catalog c SET %I = coalesce((SELECT jsonb_agg(p ORDER BY i)
                                                                FROM jsonb_array_elements(c.%I) WITH ORDINALITY AS e (p, i)
                                                               WHERE p ->> ''name'' <> $2), ''[]'')
                     WHERE c.classname = $1 RETURNING *', v_list, v_list)
       INTO v_row USING p_class, p_name;
    IF v_rechunk AND EXISTS (SELECT FROM unnest(ARRAY[v_class.cellprotable, v_class.otherprotable]) AS u(t)
                              JOIN pg_attribute a ON a.attrelid = to_regclass(format('%I.%I', v_class.schemaname, t))
                             WHERE t IS NOT NULL AND a.attnum > 0 AND NOT a.attisdropped
                               AND a.attname NOT IN ('_geoid', '_idx', '_times', '_timem', '_timet', 'revision',
                                                     'lastrevs', 'revclosed')) THEN
        PERFORM tgsis.store_class_in_chunks(p_class);
    END IF;
    RETURN v_row;
END
$$;

COMMENT ON FUNCTION tgsis.drop_property(text, text, text, boolean) IS
    'drop a property of a feature class (tgsis_admin members), in every version; refused (TG202) while a row of any version holds a value unless p_force (the count: distinct key and value over every version); the last property column of a table in chunks is dropped from rows (the class stored as rows for it, its tables keeping properties back in chunks after); p_kind (feature, cell, instant) when the name is in more than one list; updates tgsis.catalog, the views and the versioning triggers; returns the catalog row';
