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
    -- every registered storage table, tgsis.geometry last
    FOR v_table IN SELECT tablename FROM tgsis.model_tables WHERE geoidcolumn IS NOT NULL
                    ORDER BY model = 0, iudorder DESC, tablename LOOP
        EXECUTE format('DELETE FROM %s WHERE geoid = ANY ($1)', tgsis.storage_table('tgsis', v_table)) USING p_geoids;
    END LOOP;
END
$$;

COMMENT ON FUNCTION tgsis.delete_stored_geometries(bigint[]) IS
    'physically delete geometries from every registered storage table (tgsis.model_tables) of all versions, tgsis.geometry last; used when a feature class is dropped';
