-- tgsis.delete_stored_geometries(geoids): physically remove geometries from the storage of every version.
-- For dropping a whole feature class, which is not a versioned change.
CREATE FUNCTION tgsis.delete_stored_geometries(p_geoids bigint[])
RETURNS void
LANGUAGE plpgsql
VOLATILE
AS $$
DECLARE
    v_table text;
BEGIN
    FOREACH v_table IN ARRAY ARRAY['vrtx', 'point', 'segment', 'trgl', 'tetra', 'atom', 'part', 'times_trgl', 'times_vrtx', 'times',
                                 'd4dvrtx', 'd4dtrgl', 'node', 'timet', 'timem', 'geometry'] LOOP
        EXECUTE format('DELETE FROM %s WHERE geoid = ANY ($1)', tgsis.storage_table('tgsis', v_table)) USING p_geoids;
    END LOOP;
END
$$;

COMMENT ON FUNCTION tgsis.delete_stored_geometries(bigint[]) IS
    'physically delete geometries (vertices, simplices, atoms, parts, instants and periods of temporal ones, geometry rows) from the storage of all versions; used when a feature class is dropped';
