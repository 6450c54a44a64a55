-- tgsis.checked_objects(objects): the distinct ids, each a stored object (a feature's geometry); TG200 naming the missing ones.
-- A model's members must be objects the session's version holds, not
-- members of collections (which belong to their collection) nor unknown ids.
CREATE FUNCTION tgsis.checked_objects(p_objects bigint[])
RETURNS bigint[]
LANGUAGE plpgsql
STABLE
SET search_path FROM CURRENT
AS $$
DECLARE
    v_missing bigint[];
BEGIN
    IF p_objects IS NULL OR array_position(p_objects, NULL) IS NOT NULL THEN
        RAISE EXCEPTION 'the objects of a model are feature ids, got %', coalesce(p_objects::text, 'NULL')
            USING ERRCODE = 'TG100', HINT = 'p_objects => ''{12, 13}''';
    END IF;
    SELECT array_agg(o ORDER BY o) INTO v_missing
      FROM (SELECT DISTINCT o FROM unnest(p_objects) o) u
     WHERE NOT EXISTS (SELECT FROM tgsis.geometry g WHERE g.geoid = u.o AND g.collection IS NULL);
    IF v_missing IS NOT NULL THEN
        RAISE EXCEPTION 'objects % are not stored features in version %', v_missing, quote_literal(tgsis.get_working_version())
            USING ERRCODE = 'TG200', HINT = 'SELECT geoid FROM tgsis.geometry lists the stored geometries';
    END IF;
    RETURN ARRAY(SELECT DISTINCT o FROM unnest(p_objects) o ORDER BY o);
END
$$;

COMMENT ON FUNCTION tgsis.checked_objects(bigint[]) IS
    'the distinct ids, ascending, when each is a stored object (not a collection member) in the session''s version; TG200 naming the others';
