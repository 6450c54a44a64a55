-- tgsis.mesh_from_postgis(geom): a PostGIS geometry as a tgsis mesh: geotype, vertices (n x 3) and cells (m x k, 0-based).
-- Why polymorphic (anyelement) and dynamic SQL: the script may not name
-- PostGIS's type (PostGIS is optional, see tgsis.ewkb_geometry), so the
-- argument is checked to be PostGIS's geometry at run time and PostGIS's
-- functions are reached through its schema, quoted. The inverse of
-- tgsis.postgis_geometry: TIN Z, POLYHEDRALSURFACE Z, (MULTI)POLYGON Z and
-- TRIANGLE Z give a SURFACE (a face of more than three corners is split into
-- a fan of triangles; a solid's boundary stays a surface: no tetrahedra are
-- made up), (MULTI)LINESTRING Z a MULTILINESTRING of its segments,
-- (MULTI)POINT Z a MULTIPOINT. Vertices that repeat the same coordinates
-- are one vertex (as the faces of a TIN share corners), numbered in order of
-- first appearance.
CREATE FUNCTION tgsis.mesh_from_postgis(p_geom anyelement)
RETURNS TABLE (geotype text, vertices double precision[], cells bigint[])
LANGUAGE plpgsql
STABLE
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_ps    name := tgsis.postgis_schema();
    v_type  text;
    v_dims  integer;
    v_holes boolean;
    v_kind  text;
BEGIN
    IF pg_typeof(p_geom) <> format('%I.geometry', v_ps)::regtype THEN
        RAISE EXCEPTION 'a % is not a PostGIS geometry', pg_typeof(p_geom)
            USING ERRCODE = 'TG100', HINT = format('give a geometry, e.g. %s.ST_GeomFromText(''TIN Z (...)'')', quote_ident(v_ps));
    END IF;
    IF p_geom IS NULL THEN
        RAISE EXCEPTION 'the geometry is NULL' USING ERRCODE = 'TG100';
    END IF;
    EXECUTE format('SELECT %1$I.st_geometrytype($1), %1$I.st_ndims($1), %1$I.st_isempty($1)', v_ps)
       INTO v_type, v_dims, v_holes USING p_geom;
    IF v_holes THEN
        RAISE EXCEPTION 'the geometry (%) is empty', v_type
            USING ERRCODE = 'TG102', HINT = 'a tgsis object has at least one vertex';
    END IF;
    IF v_dims <> 3 THEN
        RAISE EXCEPTION 'the geometry (%) has % coordinates per point, not x, y, z', v_type, v_dims
            USING ERRCODE = 'TG102',
                  HINT = CASE WHEN v_dims = 2 THEN 'ST_Force3DZ(geom) gives it z = 0' ELSE 'ST_Force3DZ(geom) drops the measure' END;
    END IF;
    v_kind := CASE WHEN v_type IN ('ST_Tin', 'ST_Triangle', 'ST_Polygon', 'ST_MultiPolygon', 'ST_PolyhedralSurface') THEN 'SURFACE'
                   WHEN v_type IN ('ST_LineString', 'ST_MultiLineString') THEN 'MULTILINESTRING'
                   WHEN v_type IN ('ST_Point', 'ST_MultiPoint') THEN 'MULTIPOINT' END;
    IF v_kind IS NULL THEN
        RAISE EXCEPTION 'a PostGIS % has no tgsis geotype', v_type
            USING ERRCODE = 'TG102',
                  HINT = 'give a TIN, POLYHEDRALSURFACE, (MULTI)POLYGON or TRIANGLE (a SURFACE), a (MULTI)LINESTRING or a (MULTI)POINT, with Z; ST_Dump splits a collection';
    END IF;
    IF v_kind = 'SURFACE' THEN
        -- every corner of every face's outer ring (the ring closes on its first corner)
        EXECUTE format($q$
            SELECT EXISTS (SELECT FROM %1$I.st_dumppoints($1) d WHERE d.path[array_length(d.path, 1) - 1] > 1)$q$, v_ps)
           INTO v_holes USING p_geom;
        IF v_holes THEN
            RAISE EXCEPTION 'a face of the % has holes (inner rings)', v_type
                USING ERRCODE = 'TG102', HINT = 'triangulate it first (ST_Tesselate with SFCGAL, or ST_TriangulatePolygon)';
        END IF;
    END IF;
    -- window functions only (no self-joins of the points, which the planner may nest): linear in the points
    RETURN QUERY EXECUTE format($q$
        WITH p AS (   -- the points in order; part = the face or line, pos = the point in it
            SELECT row_number() OVER () AS ord,
                   CASE WHEN array_length(d.path, 1) >= 2 AND $2 = 'SURFACE' THEN d.path[array_length(d.path, 1) - 2]
                        WHEN array_length(d.path, 1) >= 2 THEN d.path[array_length(d.path, 1) - 1]
                        ELSE 1 END AS part,
                   d.path[array_length(d.path, 1)] AS pos,
                   %1$I.st_x(d.geom) AS x, %1$I.st_y(d.geom) AS y, %1$I.st_z(d.geom) AS z
              FROM %1$I.st_dumppoints($1) d
        ), f AS (     -- the first appearance of each position
            SELECT p.*, min(p.ord) OVER (PARTITION BY p.x, p.y, p.z) AS firstord FROM p
        ), v AS (     -- one vertex per distinct position, numbered by first appearance
            SELECT f.*, dense_rank() OVER (ORDER BY f.firstord) - 1 AS vid,
                   count(*) OVER (PARTITION BY f.part) AS n
              FROM f
        ), w AS (
            SELECT v.ord, v.pos, v.n, v.vid, v.x, v.y, v.z, v.firstord,
                   first_value(v.vid) OVER (PARTITION BY v.part ORDER BY v.pos) AS first,
                   lead(v.vid) OVER (PARTITION BY v.part ORDER BY v.pos) AS next
              FROM v
        )
        SELECT $2,
               (SELECT array_agg(ARRAY[w.x, w.y, w.z] ORDER BY w.vid) FROM w WHERE w.ord = w.firstord),
               (SELECT array_agg(CASE $2 WHEN 'SURFACE' THEN ARRAY[w.first, w.vid, w.next]     -- faces: fans from the first corner
                                         WHEN 'MULTILINESTRING' THEN ARRAY[w.vid, w.next]      -- lines: consecutive points
                                         ELSE ARRAY[w.vid] END ORDER BY w.ord)
                  FROM w
                 WHERE CASE $2 WHEN 'SURFACE' THEN w.pos BETWEEN 2 AND w.n - 2
                               WHEN 'MULTILINESTRING' THEN w.next IS NOT NULL
                               ELSE true END)
        $q$, v_ps)
        USING p_geom, v_kind;
END
$$;

COMMENT ON FUNCTION tgsis.mesh_from_postgis(anyelement) IS
    'a PostGIS geometry with Z as a tgsis mesh (geotype; vertices n x 3; cells m x k of 0-based vertex positions): TIN, POLYHEDRALSURFACE, (MULTI)POLYGON, TRIANGLE give a SURFACE (faces fanned into triangles), (MULTI)LINESTRING a MULTILINESTRING of segments, (MULTI)POINT a MULTIPOINT; equal positions are one vertex';
