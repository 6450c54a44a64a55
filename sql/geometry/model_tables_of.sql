-- tgsis.model_tables_of(geoids): the registered storage tables holding rows of these geometries, children first.
-- What deleting geometries must empty: the tables of their models (those of a
-- geotype only when one of them has it), then the geometry core. One place
-- that turns the registry into a deletion order, for tgsis.delete_geometry.
CREATE FUNCTION tgsis.model_tables_of(p_geoids bigint[])
RETURNS SETOF text
LANGUAGE plpgsql
STABLE
AS $$
BEGIN
    -- (PL/pgSQL: the storage tables do not exist yet when the extension script runs)
    RETURN QUERY
    SELECT t.tablename
      FROM tgsis.model_tables t
     WHERE t.geoidcolumn IS NOT NULL
       AND (t.model = 0
        OR EXISTS (SELECT FROM tgsis.geometry g JOIN tgsis.data_models m ON m.timemodel = g.timemodel
                    WHERE g.geoid = ANY (p_geoids) AND m.model = t.model
                      AND (t.geotype IS NULL OR t.geotype = g.geotype)))
     ORDER BY t.model = 0, t.tablename = 'geometry', t.iudorder DESC, t.tablename;
END
$$;

COMMENT ON FUNCTION tgsis.model_tables_of(bigint[]) IS
    'storage tables (tgsis.model_tables) that may hold rows of these geometries, in deletion order: the models'' tables children first, tgsis.geometry last';
