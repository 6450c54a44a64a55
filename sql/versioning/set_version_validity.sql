-- tgsis.set_version_validity(version, valid_from, valid_to): the period [from, to) in which a version was believed true.
-- NULL valid_to: still believed; NULL valid_from: no period.
CREATE FUNCTION tgsis.set_version_validity(p_version text, p_valid_from timestamptz, p_valid_to timestamptz DEFAULT NULL)
RETURNS void
LANGUAGE plpgsql
VOLATILE
SECURITY DEFINER
SET search_path = pg_catalog, pg_temp
AS $$
BEGIN
    PERFORM tgsis.require_version_owner(tgsis.version_id(p_version), 'set the validity of');
    IF p_valid_to IS NOT NULL AND (p_valid_from IS NULL OR p_valid_to <= p_valid_from) THEN
        RAISE EXCEPTION 'validity period [%, %) of version % is empty', p_valid_from, p_valid_to, quote_literal(p_version)
            USING ERRCODE = 'TG100', HINT = 'valid_to must be later than valid_from (NULL: still believed)';
    END IF;
    UPDATE tgsis.versions SET valid_from = p_valid_from, valid_to = p_valid_to
     WHERE versionid = tgsis.version_id(p_version);
END
$$;

COMMENT ON FUNCTION tgsis.set_version_validity(text, timestamptz, timestamptz) IS
    'set the period [valid_from, valid_to) in which a version was believed true (valid_to NULL: still believed; valid_from NULL: none)';
