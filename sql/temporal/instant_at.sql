-- tgsis.instant_at(geoid, t, convention): the instant of a model-2 surface whose shape it has at t, or NULL (none then).
-- left-closed: the last instant <= t; right-closed: the first instant >= t.
-- Before the first instant: NULL; after the last: the last if the geometry
-- is alive, else NULL.
CREATE FUNCTION tgsis.instant_at(p_geoid bigint, p_t double precision, p_convention text DEFAULT 'left')
RETURNS double precision
LANGUAGE sql
STABLE
PARALLEL SAFE
AS $$
    SELECT CASE
               WHEN tgsis.checked_time(p_t) < s.first THEN NULL
               WHEN p_t > s.last THEN CASE WHEN g.alive THEN s.last END
               WHEN lower(p_convention) = 'left'
                   THEN (SELECT max(i.times) FROM tgsis.times i WHERE i.geoid = p_geoid AND i.times <= p_t)
               ELSE (SELECT min(i.times) FROM tgsis.times i WHERE i.geoid = p_geoid AND i.times >= p_t)
           END
      FROM tgsis.geometry g,
           LATERAL (SELECT min(i.times) AS first, max(i.times) AS last FROM tgsis.times i WHERE i.geoid = p_geoid) s
     WHERE g.geoid = p_geoid AND g.timemodel = 'INSTANTS'
       -- a one-time filter, checked whatever t: a bad convention is an error, not an empty answer
       AND tgsis.checked_convention(p_convention) IS NOT NULL
$$;

COMMENT ON FUNCTION tgsis.instant_at(bigint, double precision, text) IS
    'model 2: the instant whose surface holds at t under the left- or right-closed step convention; NULL before the first instant, and after the last unless the geometry is alive';
