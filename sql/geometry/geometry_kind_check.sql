-- tgsis.geometry_kind_check(): the CHECK expression of tgsis.geometry's (geotype, timemodel) pairs, from the registry.
-- Each data model says which geotypes its geometries have; a CHECK built
-- from the rows (not typed in the table) follows the registry when a model
-- is added (tgsis.create_storage re-creates the constraint then). Not a
-- foreign key: every geometry insert would lock a registry row.
CREATE FUNCTION tgsis.geometry_kind_check()
RETURNS text
LANGUAGE sql
STABLE
AS $$
    SELECT string_agg(format('(timemodel = %L AND geotype = ANY (%L::text[]))', m.timemodel, m.geotypes), ' OR '
                      ORDER BY m.model)
      FROM tgsis.data_models m
     WHERE m.model > 0
$$;

COMMENT ON FUNCTION tgsis.geometry_kind_check() IS
    'CHECK expression (text) allowing exactly the (timemodel, geotype) pairs of the registered data models (tgsis.data_models); used for the constraint geometry_kind of tgsis.geometry';
