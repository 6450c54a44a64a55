-- tgsis.check_unchanged(geoid, fingerprint, revision): TG304 unless the object is as it was checked out.
-- Takes tgsis.feature_write_lock first, so that of two check-ins of the same
-- object from the same base the second waits for the first and then sees
-- its change. p_revision (the working revision at check-out) only serves
-- the message.
CREATE FUNCTION tgsis.check_unchanged(p_geoid bigint, p_fingerprint text, p_revision integer DEFAULT NULL)
RETURNS void
LANGUAGE plpgsql
VOLATILE
AS $$
DECLARE
    v_now      text;
    v_version  text := tgsis.get_working_version();
BEGIN
    IF p_geoid IS NULL OR p_fingerprint IS NULL THEN
        RAISE EXCEPTION 'check_unchanged needs a geoid and the fingerprint taken at check-out, got % and %',
                        coalesce(p_geoid::text, 'NULL'), coalesce(quote_literal(p_fingerprint), 'NULL')
            USING ERRCODE = 'TG100', HINT = 'SELECT tgsis.object_fingerprint(geoid) at check-out gives the fingerprint';
    END IF;
    PERFORM tgsis.require_read_committed('a check-in');
    PERFORM tgsis.feature_write_lock(p_geoid);
    v_now := tgsis.object_fingerprint(p_geoid);
    IF v_now IS NULL THEN
        RAISE EXCEPTION 'feature % was deleted from version % since it was checked out%', p_geoid, quote_literal(v_version),
                        coalesce(format(' (at revision %s)', p_revision), '')
            USING ERRCODE = 'TG304',
                  HINT = 'insert the edited mesh as a new feature, or check out another feature';
    END IF;
    IF v_now IS DISTINCT FROM p_fingerprint THEN
        RAISE EXCEPTION 'feature % was changed in version % since it was checked out%', p_geoid, quote_literal(v_version),
                        coalesce(format(' (at revision %s)', p_revision), '')
            USING ERRCODE = 'TG304',
                  DETAIL = 'Another writer changed the object meanwhile; checking in would overwrite that change.',
                  HINT = 'check in into a new child version (on_conflict="child", tgsis checkin --on-conflict child) and merge, or check out again and redo the edit';
    END IF;
END
$$;

COMMENT ON FUNCTION tgsis.check_unchanged(bigint, text, integer) IS
    'lock a feature for writing (tgsis.feature_write_lock) and raise TG304 unless its fingerprint is still the one taken at check-out';
