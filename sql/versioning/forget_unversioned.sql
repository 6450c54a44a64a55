-- tgsis.forget_unversioned(geoids): drop the records of unversioned features of which no row is left.
-- Called after a geometry is deleted (tgsis.delete_geometry). SECURITY
-- DEFINER (the registry is tgsis's alone), but it only forgets geoids whose
-- tgsis.geometry row is gone from storage, in every revision, so any role
-- may call it: a geometry that exists keeps its record. Returns how many it
-- forgot.
CREATE FUNCTION tgsis.forget_unversioned(p_geoids bigint[])
RETURNS bigint
LANGUAGE plpgsql
VOLATILE
SECURITY DEFINER
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_count bigint;
BEGIN
    EXECUTE format('DELETE FROM tgsis.unversioned_features u WHERE u.geoid = ANY ($1) '
                   'AND NOT EXISTS (SELECT FROM %s g WHERE g.geoid = u.geoid)', tgsis.storage_table('tgsis', 'geometry'))
        USING p_geoids;
    GET DIAGNOSTICS v_count = ROW_COUNT;
    RETURN v_count;
END
$$;

COMMENT ON FUNCTION tgsis.forget_unversioned(bigint[]) IS
    'remove from tgsis.unversioned_features the geoids whose tgsis.geometry row is gone from storage (every revision); returns how many';
