-- tgsis.exists_at(geoid, t, convention): whether a geometry exists at model time t (static ones always do).
-- Every data model's rule: static geometries (model 1) and model 5's, whose
-- time, if any, is an axis of their space, always; model 2 at its instants
-- (the convention says which instant holds between two); models 3 and 4
-- from their first geometry instant to their last, for ever after if alive
-- (their frames at t). Listed after the models' frames (sources.txt). Any
-- other model is refused (TG203, tgsis.no_model_rule), not answered by
-- another model's rule.
CREATE FUNCTION tgsis.exists_at(p_geoid bigint, p_t double precision, p_convention text DEFAULT 'left')
RETURNS boolean
LANGUAGE sql
STABLE
PARALLEL SAFE
AS $$
    SELECT CASE g.timemodel
               WHEN 'STATIC' THEN true
               WHEN 'MULTIDIM' THEN true
               WHEN 'INSTANTS' THEN tgsis.instant_at(p_geoid, p_t, p_convention) IS NOT NULL
               WHEN 'GMAP' THEN EXISTS (SELECT FROM tgsis.gmap_frame(p_geoid, p_t))
               WHEN 'EVOLVING' THEN EXISTS (SELECT FROM tgsis.evolving_frame(p_geoid, p_t))
               -- another model is refused (TG203), never answered by one of these rules
               ELSE tgsis.no_model_rule(g.timemodel, 'tgsis.exists_at', '{STATIC,MULTIDIM,INSTANTS,GMAP,EVOLVING}')
           END
      FROM tgsis.geometry g
     WHERE g.geoid = p_geoid
       AND tgsis.checked_convention(p_convention) IS NOT NULL  -- an error for every model, not only model 2
$$;

COMMENT ON FUNCTION tgsis.exists_at(bigint, double precision, text) IS
    'whether a geometry exists at model time t: static ones and model 5''s always; temporal ones (models 2, 3, 4) from their first instant to their last (for ever after if alive); NULL if there is no such geometry';
