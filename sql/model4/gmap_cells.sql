-- tgsis.gmap_cells(geoid, level, t): the i-cells of a G-map at model time t: for each dart of the period, its cell.
-- An i-cell is an orbit of every involution but alpha_i, computed set-based
-- over the darts of the topology period containing t (tgsis.cell_labels);
-- cell numbers the cells 0, 1, ... in the order of their least dart, as
-- tgsis.gmaps.GMap.cells does for the snapshot. VOLATILE: tgsis.cell_labels
-- works in a temporary table.
CREATE FUNCTION tgsis.gmap_cells(p_geoid bigint, p_level integer, p_t double precision)
RETURNS TABLE (dartid bigint, cell bigint, firstdart bigint)
LANGUAGE plpgsql
VOLATILE
SET search_path FROM CURRENT
AS $$
DECLARE
    v_n       smallint;
    v_timem   double precision;
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
    RETURN QUERY SELECT * FROM tgsis.cell_labels(p_geoid, p_level, 'tgsis.gmap_dart', 'tgsis.gmap_alpha', v_timem);
END
$$;

COMMENT ON FUNCTION tgsis.gmap_cells(bigint, integer, double precision) IS
    'model 4: the level-cells (orbits of every involution but alpha_level) of the G-map at t: each dart of the period with its cell number (0.. in the order of the cells'' least darts, as GMap.cells) and the cell''s least dart; none when it does not exist at t';
