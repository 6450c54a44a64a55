-- tgsis.feature_write_lock(geoid): serialise writers of one stored feature until the transaction ends.
-- The object write lock (tgsis.object_write_lock) of object class 'feature':
-- check-in, save and delete of the feature take it before they look at it,
-- so that two of them never both decide from the same state, and writes
-- through the versioned views (which hold it shared) are never in flight
-- meanwhile. With feature versioning off, raw SQL writes on the plain tables
-- take no lock: they are not seen (docs/comparison.md).
CREATE FUNCTION tgsis.feature_write_lock(p_geoid bigint)
RETURNS void
LANGUAGE sql
VOLATILE
AS $$
    SELECT tgsis.object_write_lock('feature', ARRAY[p_geoid::text])
$$;

COMMENT ON FUNCTION tgsis.feature_write_lock(bigint) IS
    'take the exclusive object write lock of a feature (tgsis.object_write_lock(''feature'', ...)) that check-in, save and delete hold while they decide from its state';
