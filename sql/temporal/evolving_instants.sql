-- tgsis.evolving_instants(geoid): every geometry instant of a model-3 surface with what its values are linear to and how long its period lasts.
-- timem / next_timem: its topology period [timem, next_timem) (next_timem NULL
-- for the last period); t_next: the next geometry instant of the period (NULL
-- at the period's last); hold: whether the values of the period's last
-- instant hold after it (until the next period, or for ever if alive).
CREATE FUNCTION tgsis.evolving_instants(p_geoid bigint)
RETURNS TABLE (timem double precision, next_timem double precision, timet double precision,
               t_next double precision, hold boolean)
LANGUAGE sql
STABLE
PARALLEL SAFE
AS $$
    SELECT i.timem, m.next_timem, i.timet, lead(i.timet) OVER (PARTITION BY i.timem ORDER BY i.timet),
           m.next_timem IS NOT NULL OR g.alive
      FROM tgsis.timet i
      JOIN (SELECT t.timem, lead(t.timem) OVER (ORDER BY t.timem) AS next_timem
              FROM tgsis.timem t
             WHERE t.geoid = p_geoid) m ON m.timem = i.timem
      JOIN tgsis.geometry g ON g.geoid = p_geoid
     WHERE i.geoid = p_geoid
$$;

COMMENT ON FUNCTION tgsis.evolving_instants(bigint) IS
    'model 3: geometry instants of a surface with their period [timem, next_timem), the next geometry instant of the period (t_next) and whether the last values hold after the period (hold)';
