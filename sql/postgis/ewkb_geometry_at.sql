-- tgsis.ewkb_geometry_at(geoid, t, convention, srid): a geometry's shape at model time t as PostGIS EWKB, or NULL when it does not exist then.
-- Why: models 2 and 3 have a shape only at a time; this is tgsis.vertices_at
-- and tgsis.triangles_at (the same snapshot as Python's get_at, to the bit)
-- written as a TIN Z. NULL rather than an empty TIN outside the feature's
-- life, as get_at gives None. Static geometries: their one shape at every t.
-- Built without PostGIS (see tgsis.ewkb_geometry for why).
CREATE FUNCTION tgsis.ewkb_geometry_at(p_geoid bigint, p_t double precision, p_convention text DEFAULT 'left',
                                       p_srid integer DEFAULT NULL)
RETURNS bytea
LANGUAGE plpgsql
STABLE
PARALLEL SAFE
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_z     constant integer := -2147483648;
    v_zsrid constant integer := -1610612736;
    v_model text;
    v_count integer;
    v_body  bytea;
BEGIN
    PERFORM tgsis.checked_time(p_t), tgsis.checked_convention(p_convention);
    SELECT g.timemodel INTO v_model FROM tgsis.geometry g WHERE g.geoid = p_geoid;
    IF NOT FOUND THEN
        RAISE EXCEPTION 'geometry % does not exist', coalesce(p_geoid::text, 'NULL')
            USING ERRCODE = 'TG200', HINT = 'SELECT _geoid FROM <class> lists the features of a class';
    END IF;
    IF v_model NOT IN ('INSTANTS', 'EVOLVING') THEN   -- static (or no PostGIS form: ewkb_geometry says so)
        RETURN tgsis.ewkb_geometry(p_geoid, p_srid);
    END IF;
    IF p_srid < 0 THEN
        RAISE EXCEPTION 'SRID % is not an id >= 0', p_srid USING ERRCODE = 'TG100';
    END IF;
    IF NOT tgsis.exists_at(p_geoid, p_t, p_convention) THEN
        RETURN NULL;
    END IF;
    WITH v AS MATERIALIZED (
        SELECT v.vrtxid, float8send(v.x) || float8send(v.y) || float8send(v.z) AS p
          FROM tgsis.vertices_at(p_geoid, p_t, p_convention) v
    )
    SELECT count(*), string_agg('\x00'::bytea || int4send(v_z + 17) || int4send(1) || int4send(4)
                                || a.p || b.p || c.p || a.p, ''::bytea ORDER BY t.trglid)
      INTO v_count, v_body
      FROM tgsis.triangles_at(p_geoid, p_t, p_convention) t
      JOIN v a ON a.vrtxid = t.vrtxid1
      JOIN v b ON b.vrtxid = t.vrtxid2
      JOIN v c ON c.vrtxid = t.vrtxid3;
    RETURN '\x00'::bytea
           || CASE WHEN p_srid IS NULL THEN int4send(v_z + 16) ELSE int4send(v_zsrid + 16) || int4send(p_srid) END
           || int4send(v_count) || coalesce(v_body, '');
END
$$;

COMMENT ON FUNCTION tgsis.ewkb_geometry_at(bigint, double precision, text, integer) IS
    'a geometry''s shape at model time t as PostGIS EWKB (a temporal surface: TIN Z of tgsis.vertices_at and triangles_at; a static geometry: as tgsis.ewkb_geometry), NULL when it does not exist at t; built without PostGIS';
