-- tgsis.merge_sliced_hint(version, action, geoid, slices): the hint of a psql merge of a temporal surface that refuses what only the Python client merges.
-- Shared by tgsis.merge_instants_by_slice and tgsis.merge_periods_by_slice:
-- the command and the Python call that merge the object slice by slice (its
-- regions), the version name shell-quoted for the command and JSON-quoted
-- for Python, else the whole-object solution in SQL. p_slices words how
-- ('instant by instant').
CREATE FUNCTION tgsis.merge_sliced_hint(p_version text, p_action text, p_geoid bigint, p_slices text)
RETURNS text
LANGUAGE sql
STABLE
SET search_path = pg_catalog, pg_temp
AS $$
    SELECT format('`tgsis version %s %s` or tgsis.%s_version(conn, %s) in Python merges it %s '
                  '(its regions); else solve it as a whole object: '
                  'SELECT tgsis.resolve_conflict(%L, ''feature'', %L, ''parent''|''child''|''manual'')',
                  p_action, tgsis.shell_quote(p_version), p_action, pg_catalog.to_json(p_version)::text, p_slices, p_version,
                  p_geoid::text)
$$;

-- internal to the psql merges, not executable by PUBLIC (tests/test_function_grants.py)
REVOKE ALL ON FUNCTION tgsis.merge_sliced_hint(text, text, bigint, text) FROM PUBLIC;

COMMENT ON FUNCTION tgsis.merge_sliced_hint(text, text, bigint, text) IS
    'the hint of a psql merge of a temporal surface refusing what only the Python client merges: the command and the Python call that merge it slice by slice, or the whole-object solution';
