-- tgsis.simplex_table(geotype): the table holding the simplices of a geotype (model 1's tables, named
-- here in the geometry core because versioning's region detection and the models above it read it).
CREATE FUNCTION tgsis.simplex_table(p_geotype text)
RETURNS text
LANGUAGE sql
IMMUTABLE
PARALLEL SAFE
AS $$
    SELECT CASE upper(p_geotype)
               WHEN 'MULTIPOINT' THEN 'point'
               WHEN 'MULTILINESTRING' THEN 'segment'
               WHEN 'SURFACE' THEN 'trgl'
               WHEN 'MULTITETRA' THEN 'tetra'
           END
$$;

COMMENT ON FUNCTION tgsis.simplex_table(text) IS
    'name of the table (in schema tgsis) holding the simplices of a geotype: point, segment, trgl, tetra; NULL for GEOMETRYCOLLECTION';
