-- tgsis.feature_write_lock(geoid): serialise writers of one stored object until the transaction ends.
-- A transaction-level advisory lock keyed by the geoid: check-in, save and
-- delete of the object take it before they look at the object, so that two
-- of them never both decide from the same state (no lost update). Writers
-- that go around these paths (raw SQL on the tables) do not take it.
CREATE FUNCTION tgsis.feature_write_lock(p_geoid bigint)
RETURNS void
LANGUAGE sql
VOLATILE
AS $$
    SELECT pg_advisory_xact_lock(hashtextextended('tgsis.object', p_geoid))
$$;

COMMENT ON FUNCTION tgsis.feature_write_lock(bigint) IS
    'take the transaction-level advisory lock that check-in, save and delete of a stored object hold while they decide from its state';
