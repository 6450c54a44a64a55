-- tgsis.exists_at(geoid, t, convention): whether a geometry exists at model time t (static ones always do).
CREATE FUNCTION tgsis.exists_at(p_geoid bigint, p_t double precision, p_convention text DEFAULT 'left')
RETURNS boolean
LANGUAGE sql
STABLE
PARALLEL SAFE
AS $$
    SELECT CASE g.timemodel
               WHEN 'STATIC' THEN true
               WHEN 'INSTANTS' THEN tgsis.instant_at(p_geoid, p_t, p_convention) IS NOT NULL
               ELSE EXISTS (SELECT FROM tgsis.evolving_frame(p_geoid, p_t))
           END
      FROM tgsis.geometry g
     WHERE g.geoid = p_geoid
       AND tgsis.checked_convention(p_convention) IS NOT NULL  -- an error for every model, not only model 2
$$;

COMMENT ON FUNCTION tgsis.exists_at(bigint, double precision, text) IS
    'whether a geometry exists at model time t: static always; temporal ones from their first instant to their last (for ever after if alive); NULL if there is no such geometry';
