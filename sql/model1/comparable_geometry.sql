-- tgsis.comparable_geometry(geoid, revisions, seen_in): the geotype of a geometry that mesh comparison can take, or a TG100/TG200 error.
-- Reads the geometry row as the session sees it (revisions NULL) or at a
-- revision set (from the versioned storage); seen_in ends the messages
-- (e.g. ' in version ''edit''').
-- The visibility test below is tgsis.visible_versions' text, kept static (tests/test_visible_versions.py compares).
CREATE FUNCTION tgsis.comparable_geometry(p_geoid bigint, p_revisions integer[], p_seen_in text DEFAULT '')
RETURNS text
LANGUAGE plpgsql
STABLE
AS $$
DECLARE
    v_geo record;
BEGIN
    IF p_geoid IS NULL THEN
        RAISE EXCEPTION 'a geometry id is required, got NULL' USING ERRCODE = 'TG100';
    END IF;
    IF p_revisions IS NULL THEN
        SELECT g.geotype, g.timemodel INTO v_geo FROM tgsis.geometry g WHERE g.geoid = p_geoid;
    ELSE
        SELECT g.geotype, g.timemodel INTO v_geo FROM tgsis.geometry_ver g
         WHERE g.geoid = p_geoid AND (g.revision = ANY (p_revisions)) IS TRUE
           AND (NOT g.revclosed OR NOT (g.lastrevs && p_revisions));
    END IF;
    IF NOT FOUND THEN
        RAISE EXCEPTION 'geometry % does not exist%', p_geoid, p_seen_in
            USING ERRCODE = 'TG200', HINT = 'SELECT geoid, geotype FROM tgsis.geometry lists the stored geometries';
    END IF;
    IF v_geo.geotype = 'GEOMETRYCOLLECTION' THEN
        RAISE EXCEPTION 'geometry % is a GEOMETRYCOLLECTION%: collections are not compared as one mesh', p_geoid, p_seen_in
            USING ERRCODE = 'TG100',
                  HINT = format('compare its members one by one: SELECT geoids FROM tgsis.geometry WHERE geoid = %s', p_geoid);
    END IF;
    IF v_geo.timemodel <> 'STATIC' THEN
        RAISE EXCEPTION 'geometry % is a temporal surface (time model %)%: only static geometries (model 1) are compared',
                        p_geoid, v_geo.timemodel, p_seen_in
            USING ERRCODE = 'TG100',
                  DETAIL = 'Its shape is in the tables of models 2 and 3, one per instant, not in tgsis.vrtx and tgsis.trgl.';
    END IF;
    RETURN v_geo.geotype;
END
$$;

COMMENT ON FUNCTION tgsis.comparable_geometry(bigint, integer[], text) IS
    'geotype of a geometry (as the session sees it, or at a revision set) that mesh comparison takes; TG200 if it does not exist, TG100 for NULL, a GEOMETRYCOLLECTION or a temporal surface';
