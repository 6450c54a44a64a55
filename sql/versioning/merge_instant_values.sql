-- tgsis.merge_instant_values(base, parent, version): one per-instant feature property row merged three ways column by column, or a conflict.
-- The rule of tgsis._merge_slices._merge_rows, which the psql merges of
-- temporal surfaces (tgsis.merge_instants_by_slice, tgsis.merge_periods_by_slice)
-- share: each side's row as text (NULL: the side has none); the parent's row
-- when the version did not change it or both changed it alike, the version's
-- when only it changed it, else column by column the side that changed it. A
-- row removed (or added) on one side and set otherwise on the other, or a
-- column both sides changed to other values, is an object-level conflict:
-- p_conflict true, p_merged NULL.
CREATE FUNCTION tgsis.merge_instant_values(p_base text[], p_parent text[], p_version text[],
                                           OUT p_conflict boolean, OUT p_merged text[])
LANGUAGE plpgsql
IMMUTABLE
PARALLEL SAFE
SET search_path = pg_catalog, pg_temp
AS $$
BEGIN
    p_conflict := false;
    IF p_parent IS NOT DISTINCT FROM p_version OR p_version IS NOT DISTINCT FROM p_base THEN
        p_merged := p_parent;
    ELSIF p_parent IS NOT DISTINCT FROM p_base THEN
        p_merged := p_version;
    ELSIF p_parent IS NULL OR p_version IS NULL OR p_base IS NULL
       OR EXISTS (SELECT FROM generate_subscripts(p_base, 1) AS i
                   WHERE p_parent[i] IS DISTINCT FROM p_version[i] AND p_version[i] IS DISTINCT FROM p_base[i]
                     AND p_parent[i] IS DISTINCT FROM p_base[i]) THEN
        p_conflict := true;
    ELSE
        p_merged := ARRAY(SELECT CASE WHEN p_version[i] IS NOT DISTINCT FROM p_base[i] THEN p_parent[i] ELSE p_version[i] END
                            FROM generate_subscripts(p_base, 1) AS i ORDER BY i);
    END IF;
END
$$;

-- internal to the psql merges, not executable by PUBLIC (tests/test_function_grants.py)
REVOKE ALL ON FUNCTION tgsis.merge_instant_values(text[], text[], text[]) FROM PUBLIC;

COMMENT ON FUNCTION tgsis.merge_instant_values(text[], text[], text[]) IS
    'one per-instant feature property row (values as text) merged three ways column by column as the Python merge merges it; p_conflict when one side removed it and the other changed it, or both changed a column to other values';
