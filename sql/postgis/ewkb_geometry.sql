-- tgsis.ewkb_geometry(geoid, srid): a static geometry as PostGIS extended WKB (big-endian), built in SQL without PostGIS.
-- Why bytes and not PostGIS's geometry type: the extension script must
-- install and restore where PostGIS is absent, so no object of the script may
-- name a PostGIS type. EWKB is PostGIS's own exchange form: ST_GeomFromEWKB
-- (and the implicit cast bytea -> geometry) read it exactly, every coordinate
-- bit for bit (float8send is the IEEE 754 value, big-endian).
-- What each geotype becomes (docs/postgis.md):
--   SURFACE            TIN Z, one TRIANGLE Z per triangle, in trglid order
--   MULTITETRA         POLYHEDRALSURFACE Z of the solid's boundary: the faces
--                      that belong to one tetrahedron only, oriented outwards
--   MULTILINESTRING    MULTILINESTRING Z, one two-point LINESTRING per segment
--   MULTIPOINT         MULTIPOINT Z, one POINT Z per point
--   GEOMETRYCOLLECTION GEOMETRYCOLLECTION Z of its members, in order
-- z is elevation, as stored (a Depth file's z are negated on the way in).
-- p_srid NULL: no SRID in the header (members of a collection); 0: unknown.
-- Temporal surfaces have no shape without a time: tgsis.ewkb_geometry_at.
CREATE FUNCTION tgsis.ewkb_geometry(p_geoid bigint, p_srid integer DEFAULT NULL)
RETURNS bytea
LANGUAGE plpgsql
STABLE
PARALLEL SAFE
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    -- EWKB type words: the wkbZ flag 0x80000000, with wkbSRID 0x20000000 when an SRID follows
    v_z      constant integer := -2147483648;
    v_zsrid  constant integer := -1610612736;
    v_geo    record;
    v_code   integer;
    v_count  integer;
    v_body   bytea;
    v_member bigint;
BEGIN
    SELECT g.geotype, g.timemodel, g.geoids INTO v_geo FROM tgsis.geometry g WHERE g.geoid = p_geoid;
    IF NOT FOUND THEN
        RAISE EXCEPTION 'geometry % does not exist', coalesce(p_geoid::text, 'NULL')
            USING ERRCODE = 'TG200', HINT = 'SELECT _geoid FROM <class> lists the features of a class';
    END IF;
    IF v_geo.geotype NOT IN ('MULTIPOINT', 'MULTILINESTRING', 'SURFACE', 'MULTITETRA', 'GEOMETRYCOLLECTION') THEN
        RAISE EXCEPTION 'geometry % is a % (data model %), which has no PostGIS form', p_geoid, v_geo.geotype, v_geo.timemodel
            USING ERRCODE = 'TG100',
                  HINT = 'PostGIS forms exist for MULTIPOINT, MULTILINESTRING, SURFACE, MULTITETRA and GEOMETRYCOLLECTION';
    END IF;
    IF v_geo.timemodel <> 'STATIC' THEN
        RAISE EXCEPTION 'geometry % is a % surface: its shape depends on the time', p_geoid, v_geo.timemodel
            USING ERRCODE = 'TG100', HINT = 'take its shape at a time t: tgsis.postgis_geometry_at(class, geoid, t)';
    END IF;
    IF p_srid < 0 THEN
        RAISE EXCEPTION 'SRID % is not an id >= 0', p_srid USING ERRCODE = 'TG100';
    END IF;
    CASE v_geo.geotype
    WHEN 'SURFACE' THEN
        v_code := 16;  -- TIN
        SELECT count(*), string_agg('\x00'::bytea || int4send(v_z + 17) || int4send(1) || int4send(4)
                                    || a.p || b.p || c.p || a.p, ''::bytea ORDER BY t.trglid)
          INTO v_count, v_body
          FROM tgsis.trgl t
          CROSS JOIN LATERAL (SELECT float8send(v.x) || float8send(v.y) || float8send(v.z) AS p FROM tgsis.vrtx v
                               WHERE v.geoid = p_geoid AND v.vrtxid = t.vrtxid1) a
          CROSS JOIN LATERAL (SELECT float8send(v.x) || float8send(v.y) || float8send(v.z) AS p FROM tgsis.vrtx v
                               WHERE v.geoid = p_geoid AND v.vrtxid = t.vrtxid2) b
          CROSS JOIN LATERAL (SELECT float8send(v.x) || float8send(v.y) || float8send(v.z) AS p FROM tgsis.vrtx v
                               WHERE v.geoid = p_geoid AND v.vrtxid = t.vrtxid3) c
         WHERE t.geoid = p_geoid;
    WHEN 'MULTITETRA' THEN
        v_code := 15;  -- POLYHEDRALSURFACE
        WITH face AS (   -- the four faces of each tetrahedron, with the vertex opposite each
            SELECT t.tetraid, f.i, f.j, f.k, f.o
              FROM tgsis.tetra t
             CROSS JOIN LATERAL (VALUES (t.vrtxid1, t.vrtxid2, t.vrtxid3, t.vrtxid4), (t.vrtxid1, t.vrtxid2, t.vrtxid4, t.vrtxid3),
                                        (t.vrtxid1, t.vrtxid3, t.vrtxid4, t.vrtxid2), (t.vrtxid2, t.vrtxid3, t.vrtxid4, t.vrtxid1))
                   AS f(i, j, k, o)
             WHERE t.geoid = p_geoid
        ), border AS (   -- a face of one tetrahedron only is on the boundary (faces compared as sorted triples)
            SELECT f.*
              FROM (SELECT f.*, count(*) OVER (PARTITION BY least(f.i, f.j, f.k), greatest(f.i, f.j, f.k),
                                                            f.i + f.j + f.k - least(f.i, f.j, f.k) - greatest(f.i, f.j, f.k)) AS n
                      FROM face f) f
             WHERE f.n = 1
        ), placed AS (
            SELECT b.tetraid, b.i, b.j, b.k, pi.x AS xi, pi.y AS yi, pi.z AS zi, pj.x AS xj, pj.y AS yj, pj.z AS zj,
                   pk.x AS xk, pk.y AS yk, pk.z AS zk, po.x - pi.x AS dx, po.y - pi.y AS dy, po.z - pi.z AS dz
              FROM border b
              JOIN tgsis.vrtx pi ON pi.geoid = p_geoid AND pi.vrtxid = b.i
              JOIN tgsis.vrtx pj ON pj.geoid = p_geoid AND pj.vrtxid = b.j
              JOIN tgsis.vrtx pk ON pk.geoid = p_geoid AND pk.vrtxid = b.k
              JOIN tgsis.vrtx po ON po.geoid = p_geoid AND po.vrtxid = b.o
        ), oriented AS (   -- outwards: the normal (pj - pi) x (pk - pi) points away from the opposite vertex
            SELECT p.tetraid, p.i, p.j, p.k,
                   float8send(p.xi) || float8send(p.yi) || float8send(p.zi) AS a,
                   float8send(p.xj) || float8send(p.yj) || float8send(p.zj) AS b,
                   float8send(p.xk) || float8send(p.yk) || float8send(p.zk) AS c,
                   ((p.yj - p.yi) * (p.zk - p.zi) - (p.zj - p.zi) * (p.yk - p.yi)) * p.dx
                 + ((p.zj - p.zi) * (p.xk - p.xi) - (p.xj - p.xi) * (p.zk - p.zi)) * p.dy
                 + ((p.xj - p.xi) * (p.yk - p.yi) - (p.yj - p.yi) * (p.xk - p.xi)) * p.dz > 0 AS inwards
              FROM placed p
        )
        SELECT count(*), string_agg('\x00'::bytea || int4send(v_z + 3) || int4send(1) || int4send(4) || o.a
                                    || CASE WHEN o.inwards THEN o.c || o.b ELSE o.b || o.c END || o.a,
                                    ''::bytea ORDER BY o.tetraid, o.i, o.j, o.k)
          INTO v_count, v_body
          FROM oriented o;
    WHEN 'MULTILINESTRING' THEN
        v_code := 5;
        SELECT count(*), string_agg('\x00'::bytea || int4send(v_z + 2) || int4send(2)
                                    || float8send(a.x) || float8send(a.y) || float8send(a.z)
                                    || float8send(b.x) || float8send(b.y) || float8send(b.z), ''::bytea ORDER BY s.segid)
          INTO v_count, v_body
          FROM tgsis.segment s
          JOIN tgsis.vrtx a ON a.geoid = p_geoid AND a.vrtxid = s.vrtxid1
          JOIN tgsis.vrtx b ON b.geoid = p_geoid AND b.vrtxid = s.vrtxid2
         WHERE s.geoid = p_geoid;
    WHEN 'MULTIPOINT' THEN
        v_code := 4;
        SELECT count(*), string_agg('\x00'::bytea || int4send(v_z + 1)
                                    || float8send(a.x) || float8send(a.y) || float8send(a.z), ''::bytea ORDER BY p.pointid)
          INTO v_count, v_body
          FROM tgsis.point p
          JOIN tgsis.vrtx a ON a.geoid = p_geoid AND a.vrtxid = p.vrtxid1
         WHERE p.geoid = p_geoid;
    ELSE  -- GEOMETRYCOLLECTION (the only geotype left): its members without SRIDs of their own (the collection carries it)
        v_code := 7;
        v_count := 0;
        v_body := '';
        FOREACH v_member IN ARRAY v_geo.geoids LOOP
            v_body := v_body || tgsis.ewkb_geometry(v_member, NULL);
            v_count := v_count + 1;
        END LOOP;
    END CASE;
    RETURN '\x00'::bytea
           || CASE WHEN p_srid IS NULL THEN int4send(v_z + v_code) ELSE int4send(v_zsrid + v_code) || int4send(p_srid) END
           || int4send(v_count) || coalesce(v_body, '');
END
$$;

COMMENT ON FUNCTION tgsis.ewkb_geometry(bigint, integer) IS
    'a static geometry as PostGIS EWKB with SRID p_srid (NULL: none): SURFACE as TIN Z, MULTITETRA as the POLYHEDRALSURFACE Z of its boundary (outward faces), MULTILINESTRING Z of its segments, MULTIPOINT Z, GEOMETRYCOLLECTION Z of its members; built without PostGIS (ST_GeomFromEWKB reads it)';
