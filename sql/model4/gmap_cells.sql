-- tgsis.gmap_cells(geoid, level, t): the i-cells of a G-map at model time t: for each dart of the period, its cell.
-- An i-cell is an orbit of every involution but alpha_i. Computed set-based
-- over the period's darts: every dart starts labelled by itself, then each
-- round takes the least label among its images (one keyed join for all
-- darts) and jumps to its label's label, until nothing changes; the label is
-- then the orbit's least dart (rounds grow with the logarithm of the orbit's
-- diameter, not with the number of darts). cell numbers the cells 0, 1, ...
-- in the order of their least dart, as tgsis.gmaps.GMap.cells does for the
-- period's G-map. VOLATILE: the work table is a temporary table.
CREATE FUNCTION tgsis.gmap_cells(p_geoid bigint, p_level integer, p_t double precision)
RETURNS TABLE (dartid bigint, cell bigint, firstdart bigint)
LANGUAGE plpgsql
VOLATILE
SET search_path FROM CURRENT
AS $$
DECLARE
    v_n       smallint;
    v_timem   double precision;
    v_changed bigint;
BEGIN
    SELECT g.dimension INTO v_n FROM tgsis.gmap g WHERE g.geoid = p_geoid;
    IF NOT FOUND THEN
        RAISE EXCEPTION 'geometry % is not a stored G-map', p_geoid
            USING ERRCODE = 'TG200', HINT = 'SELECT geoid FROM tgsis.gmap lists the stored G-maps';
    END IF;
    IF p_level IS NULL OR p_level < 0 OR p_level > v_n THEN
        RAISE EXCEPTION 'cell level % is not a cell dimension of the %-G-map %', coalesce(p_level::text, 'NULL'), v_n, p_geoid
            USING ERRCODE = 'TG100', HINT = format('p_level => 0 .. %s', v_n);
    END IF;
    SELECT f.timem INTO v_timem FROM tgsis.gmap_frame(p_geoid, p_t) f;
    IF NOT FOUND THEN
        RETURN;  -- it does not exist at t
    END IF;
    DROP TABLE IF EXISTS pg_temp.tgsis_gmap_cells;
    CREATE TEMPORARY TABLE tgsis_gmap_cells (dartid bigint PRIMARY KEY, label bigint NOT NULL) ON COMMIT DROP;
    INSERT INTO pg_temp.tgsis_gmap_cells
    SELECT d.dartid, d.dartid FROM tgsis.gmap_dart d WHERE d.geoid = p_geoid AND d.timem = v_timem;
    ANALYZE pg_temp.tgsis_gmap_cells;
    LOOP
        UPDATE pg_temp.tgsis_gmap_cells w SET label = m.label
          FROM (SELECT a.dartid, min(o.label) AS label
                  FROM tgsis.gmap_alpha a
                  JOIN pg_temp.tgsis_gmap_cells o ON o.dartid = a.dartid2
                 WHERE a.geoid = p_geoid AND a.level <> p_level AND a.dartid IN (SELECT c.dartid FROM pg_temp.tgsis_gmap_cells c)
                 GROUP BY a.dartid) m
         WHERE w.dartid = m.dartid AND m.label < w.label;
        GET DIAGNOSTICS v_changed = ROW_COUNT;
        EXIT WHEN v_changed = 0;
        UPDATE pg_temp.tgsis_gmap_cells w SET label = o.label
          FROM pg_temp.tgsis_gmap_cells o
         WHERE o.dartid = w.label AND o.label < w.label;
    END LOOP;
    RETURN QUERY
    SELECT w.dartid, dense_rank() OVER (ORDER BY w.label) - 1, w.label
      FROM pg_temp.tgsis_gmap_cells w
     ORDER BY w.dartid;
    DROP TABLE pg_temp.tgsis_gmap_cells;
END
$$;

COMMENT ON FUNCTION tgsis.gmap_cells(bigint, integer, double precision) IS
    'model 4: the level-cells (orbits of every involution but alpha_level) of the G-map at t: each dart of the period with its cell number (0.. in the order of the cells'' least darts, as GMap.cells) and the cell''s least dart; none when it does not exist at t';
