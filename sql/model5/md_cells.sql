-- tgsis.md_cells(geoid, level): the level-cells of a multiply indexed G-map (model 5): for each dart, its cell.
-- Orbits of every involution but alpha_level, set-based (tgsis.cell_labels);
-- cell numbers the cells 0, 1, ... in the order of their least dart, as
-- tgsis.gmaps.GMap.cells. VOLATILE: tgsis.cell_labels works in a temporary table.
CREATE FUNCTION tgsis.md_cells(p_geoid bigint, p_level integer)
RETURNS TABLE (dartid bigint, cell bigint, firstdart bigint)
LANGUAGE plpgsql
VOLATILE
SET search_path FROM CURRENT
AS $$
DECLARE
    v_n smallint;
BEGIN
    SELECT g.dimension INTO v_n FROM tgsis.md_gmap g WHERE g.geoid = p_geoid;
    IF NOT FOUND THEN
        RAISE EXCEPTION 'geometry % is not a stored multiply indexed G-map', p_geoid
            USING ERRCODE = 'TG200', HINT = 'SELECT geoid FROM tgsis.md_gmap lists them';
    END IF;
    IF p_level IS NULL OR p_level < 0 OR p_level > v_n THEN
        RAISE EXCEPTION 'cell level % is not a cell dimension of the %-G-map %', coalesce(p_level::text, 'NULL'), v_n, p_geoid
            USING ERRCODE = 'TG100', HINT = format('p_level => 0 .. %s', v_n);
    END IF;
    RETURN QUERY SELECT * FROM tgsis.cell_labels(p_geoid, p_level, 'tgsis.md_dart', 'tgsis.md_alpha');
END
$$;

COMMENT ON FUNCTION tgsis.md_cells(bigint, integer) IS
    'model 5: the level-cells of a multiply indexed G-map: each dart with its cell number (0.. in the order of the cells'' least darts, as GMap.cells) and the cell''s least dart';
