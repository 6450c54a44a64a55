-- tgsis.object_fingerprint(geoid): a digest of everything the session's version holds of a model-1 feature.
-- Per table (the geometry row, its vertices, simplices, cell properties and
-- feature row; a collection's members too) the row count and the xor of the
-- 64-bit hashes of the rows (tgsis.table_fingerprint; bit_xor is safe: a
-- primary key never lets two equal rows cancel out), so that any insert, delete or change of
-- a value shows, whatever the row order. Read through the tables' names,
-- i.e. through the versioned views when versioning is on: it is the state
-- the session sees. Check-out keeps it; check-in compares it (no lost update).
-- Values hashed as text (timestamps, dates, the geometry row) are written
-- with fixed settings: a check-out in one session and a check-in in another
-- (another TimeZone, DateStyle or extra_float_digits) compare the same text.
CREATE FUNCTION tgsis.object_fingerprint(p_geoid bigint)
RETURNS text
LANGUAGE plpgsql
STABLE
SET DateStyle = 'ISO, YMD'
SET TimeZone = 'UTC'
SET IntervalStyle = 'postgres'
SET extra_float_digits = 1
SET bytea_output = 'hex'
AS $$
DECLARE
    v_geo     record;
    v_ids     bigint[];
    v_class   record;
    v_parts   text[] := '{}';
    v_part    text;
    v_table   text;
BEGIN
    SELECT geotype, timemodel INTO v_geo FROM tgsis.geometry WHERE geoid = p_geoid;
    IF NOT FOUND THEN
        RETURN NULL;
    END IF;
    IF v_geo.timemodel <> 'STATIC' THEN
        RAISE EXCEPTION 'geometry % is temporal (%): fingerprints are of static (model-1) objects', p_geoid, v_geo.timemodel
            USING ERRCODE = 'TG100';
    END IF;
    SELECT p_geoid || coalesce(array_agg(geoid ORDER BY geoid), '{}') INTO v_ids FROM tgsis.geometry WHERE collection = p_geoid;
    -- rows of the geometry and feature tables hash as text: cube (bbox) and some
    -- feature property types have no hash function, and there are few such rows
    SELECT count(*) || ':' || coalesce(bit_xor(hashtextextended(g::text, 0)), 0) INTO v_part
      FROM tgsis.geometry g WHERE g.geoid = ANY (v_ids);
    v_parts := v_parts || ('geometry ' || v_part);
    v_parts := v_parts || ('vrtx ' || tgsis.table_fingerprint('tgsis', 'vrtx', 'geoid', 'vrtxid', v_ids));
    v_parts := v_parts || ('atom ' || tgsis.table_fingerprint('tgsis', 'atom', 'geoid', 'vrtxid', v_ids));
    v_parts := v_parts || ('part ' || tgsis.table_fingerprint('tgsis', 'part', 'geoid', 'firstid', v_ids));
    FOR v_table IN SELECT DISTINCT tgsis.simplex_table(geotype) FROM tgsis.geometry
                    WHERE geoid = ANY (v_ids) AND geotype <> 'GEOMETRYCOLLECTION' ORDER BY 1 LOOP
        v_parts := v_parts || (v_table || ' ' || tgsis.table_fingerprint(
            'tgsis', v_table, 'geoid', CASE v_table WHEN 'point' THEN 'pointid' WHEN 'segment' THEN 'segid'
                                                     WHEN 'trgl' THEN 'trglid' ELSE 'tetraid' END, v_ids));
    END LOOP;
    FOR v_class IN SELECT schemaname, featuretable, cellprotable, otherprotable FROM tgsis.catalog
                    WHERE geotype = v_geo.geotype AND timemodel = 'STATIC' ORDER BY classname LOOP
        EXECUTE format('SELECT count(*) || '':'' || coalesce(bit_xor(hashtextextended(f::text, 0)), 0) FROM %I.%I f WHERE f._geoid = $1',
                       v_class.schemaname, v_class.featuretable)
           INTO v_part USING p_geoid;
        v_parts := v_parts || (v_class.featuretable || ' ' || v_part);
        v_parts := v_parts || (v_class.cellprotable || ' ' || tgsis.table_fingerprint(
            v_class.schemaname, v_class.cellprotable, '_geoid', '_idx', v_ids));
        IF v_class.otherprotable IS NOT NULL THEN
            v_parts := v_parts || (v_class.otherprotable || ' ' || tgsis.table_fingerprint(
                v_class.schemaname, v_class.otherprotable, '_geoid', '_idx', v_ids));
        END IF;
    END LOOP;
    RETURN md5(array_to_string(v_parts, '|'));
END
$$;

COMMENT ON FUNCTION tgsis.object_fingerprint(bigint) IS
    'digest (md5 of per-table row counts and xor of row hashes) of a static feature''s rows as the session''s version sees them: geometry, vertices, simplices, atoms, parts, cell properties, feature row, members; NULL when the geometry does not exist';
