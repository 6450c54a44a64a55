-- tgsis.merge_ids_text(ids): ids for a message, as tgsis.merge3.ids_text writes them (the first ten, then how many).
CREATE FUNCTION tgsis.merge_ids_text(p_ids text[])
RETURNS text
LANGUAGE sql
IMMUTABLE
PARALLEL SAFE
AS $$
    SELECT array_to_string(p_ids[1:10], ', ')
           || CASE WHEN cardinality(p_ids) > 10 THEN format(', ... (%s in all)', cardinality(p_ids)) ELSE '' END
$$;

COMMENT ON FUNCTION tgsis.merge_ids_text(text[]) IS
    'ids for a message as tgsis.merge3.ids_text writes them: the first ten, then how many in all';

-- internal to the merges: reached only through the SECURITY DEFINER merge, refresh, find_conflicts and
-- resolve functions, as their owner; not executable by PUBLIC (tests/test_function_grants.py)
REVOKE ALL ON FUNCTION tgsis.merge_ids_text(text[]) FROM PUBLIC;
