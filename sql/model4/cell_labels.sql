-- tgsis.cell_labels(geoid, level, darts, alpha, period): the level-cells of stored G-map rows: for each dart, its cell.
-- Shared by tgsis.gmap_cells (model 4, the darts of one topology period) and
-- tgsis.md_cells (model 5, every dart). An i-cell is an orbit of every
-- involution but alpha_i. Set-based over the darts: every dart starts
-- labelled by itself, then each round takes the least label among its
-- images (one keyed join for all darts) and jumps to its label's label,
-- until nothing changes; the label is then the orbit's least dart (rounds
-- grow with the logarithm of the orbit's diameter, not with the number of
-- darts). cell numbers the cells 0, 1, ... in the order of their least dart,
-- as tgsis.gmaps.GMap.cells does. VOLATILE: the work table is temporary.
-- The tables are regclass (quoted by their output): no caller text reaches the SQL.
CREATE FUNCTION tgsis.cell_labels(p_geoid bigint, p_level integer, p_dart regclass, p_alpha regclass,
                                  p_timem double precision DEFAULT NULL)
RETURNS TABLE (dartid bigint, cell bigint, firstdart bigint)
LANGUAGE plpgsql
VOLATILE
SET search_path FROM CURRENT
AS $$
DECLARE
    v_changed bigint;
BEGIN
    DROP TABLE IF EXISTS pg_temp.tgsis_cell_labels;
    CREATE TEMPORARY TABLE tgsis_cell_labels (dartid bigint PRIMARY KEY, label bigint NOT NULL) ON COMMIT DROP;
    EXECUTE format('INSERT INTO pg_temp.tgsis_cell_labels SELECT d.dartid, d.dartid FROM %s d WHERE d.geoid = $1 %s',
                   p_dart, CASE WHEN p_timem IS NOT NULL THEN 'AND d.timem = $2' ELSE '' END)
        USING p_geoid, p_timem;
    ANALYZE pg_temp.tgsis_cell_labels;
    LOOP
        EXECUTE format(
            'UPDATE pg_temp.tgsis_cell_labels w SET label = m.label
               FROM (SELECT a.dartid, min(o.label) AS label
                       FROM %s a
                       JOIN pg_temp.tgsis_cell_labels o ON o.dartid = a.dartid2
                      WHERE a.geoid = $1 AND a.level <> $2
                        AND a.dartid IN (SELECT c.dartid FROM pg_temp.tgsis_cell_labels c)
                      GROUP BY a.dartid) m
              WHERE w.dartid = m.dartid AND m.label < w.label', p_alpha) USING p_geoid, p_level;
        GET DIAGNOSTICS v_changed = ROW_COUNT;
        EXIT WHEN v_changed = 0;
        UPDATE pg_temp.tgsis_cell_labels w SET label = o.label
          FROM pg_temp.tgsis_cell_labels o
         WHERE o.dartid = w.label AND o.label < w.label;
    END LOOP;
    RETURN QUERY
    SELECT w.dartid, dense_rank() OVER (ORDER BY w.label) - 1, w.label
      FROM pg_temp.tgsis_cell_labels w
     ORDER BY w.dartid;
    DROP TABLE pg_temp.tgsis_cell_labels;
END
$$;

COMMENT ON FUNCTION tgsis.cell_labels(bigint, integer, regclass, regclass, double precision) IS
    'the level-cells (orbits of every involution but alpha_level) of a stored G-map''s darts (those of one topology period when timem is given): each dart with its cell number (0.. by least dart, as GMap.cells) and the cell''s least dart; shared by tgsis.gmap_cells and tgsis.md_cells';
