-- tgsis.instant_periods(geoid, convention): every instant of a model-2 surface with the interval in which its shape and values hold.
-- left-closed: '[t_i, t_i+1)'; the last instant '[t_k, t_k]', or '[t_k,)' if
-- the geometry is alive. right-closed: the first instant '[t_0, t_0]', then
-- '(t_i-1, t_i]'; the last '(t_k-1,)' if alive. The intervals do not overlap
-- and cover the feature's life, as tgsis.instant_at chooses.
CREATE FUNCTION tgsis.instant_periods(p_geoid bigint, p_convention text DEFAULT 'left')
RETURNS TABLE (times double precision, period tgsis.timerange)
LANGUAGE sql
STABLE
PARALLEL SAFE
AS $$
    SELECT s.times,
           CASE WHEN tgsis.checked_convention(p_convention) = 'left'
                THEN tgsis.modeltime_range(s.times, CASE WHEN s.next IS NOT NULL THEN s.next WHEN NOT g.alive THEN s.times END,
                                     CASE WHEN s.next IS NULL AND NOT g.alive THEN '[]' ELSE '[)' END)
                ELSE tgsis.modeltime_range(coalesce(s.prev, s.times), CASE WHEN s.next IS NOT NULL OR NOT g.alive THEN s.times END,
                                     CASE WHEN s.prev IS NULL THEN '[]' ELSE '(]' END)
           END
      FROM (SELECT i.times, lag(i.times) OVER w AS prev, lead(i.times) OVER w AS next
              FROM tgsis.times i
             WHERE i.geoid = p_geoid
            WINDOW w AS (ORDER BY i.times)) s
      JOIN tgsis.geometry g ON g.geoid = p_geoid
$$;

COMMENT ON FUNCTION tgsis.instant_periods(bigint, text) IS
    'model 2: each instant of a surface with the interval in which it holds under the left- or right-closed step convention (unbounded after the last instant of an alive geometry)';
