-- tgsis.merge_changed_keys(table, object key, key columns, geoid, since): the keys of an object's rows some revision set sees otherwise than another.
-- The first read of the psql merges of temporal surfaces
-- (tgsis.merge_instants_by_slice: (instant, id); tgsis.merge_periods_by_slice:
-- the period), as tgsis.db._merge_states reads the change first: the
-- distinct values of the columns p_keys (as text, in that order) of the rows
-- of object p_geoid (column p_okey) of a versioned table's storage written or
-- closed in one of the revisions p_since (those not in all three of the
-- base, parent and version sets). Read through tgsis.storage_run: the
-- caller's rights, or the table owner's runner as tgsis's owner. Stored in
-- chunks (model 2's time tables: tgsis.storage_row_versions), every slot of a
-- chunk version written or closed there: more keys than changed, which the
-- merge compares state by state (a key no state sees otherwise merges to itself).
CREATE FUNCTION tgsis.merge_changed_keys(p_table tgsis.versioned_tables, p_okey text, p_keys text[], p_geoid bigint,
                                         p_since integer[])
RETURNS SETOF text[]
LANGUAGE plpgsql
VOLATILE
SET search_path = pg_catalog, pg_temp
AS $$
BEGIN
    RETURN QUERY
    SELECT r FROM tgsis.storage_run(p_table, false, format(
               'SELECT DISTINCT ARRAY[%s] FROM %s v WHERE v.%I = $1[1]::bigint
                   AND (v.revision = ANY ($2) OR (v.revclosed AND v.lastrevs && $2))',
               (SELECT string_agg(format('v.%I::text', k.c), ', ' ORDER BY k.o) FROM unnest(p_keys) WITH ORDINALITY AS k(c, o)),
               tgsis.storage_row_versions(p_table.schemaname, p_table.tablename), p_okey),
           p_1 => ARRAY[p_geoid::text], p_2 => p_since) AS r;
END
$$;

-- internal to the psql merges, not executable by PUBLIC (tests/test_function_grants.py)
REVOKE ALL ON FUNCTION tgsis.merge_changed_keys(tgsis.versioned_tables, text, text[], bigint, integer[]) FROM PUBLIC;

COMMENT ON FUNCTION tgsis.merge_changed_keys(tgsis.versioned_tables, text, text[], bigint, integer[]) IS
    'the distinct keys (the given columns, as text) of an object''s rows of a versioned table written or closed in the given revisions: what the psql merges of temporal surfaces read first';
