-- tgsis.disable_versioning(table, force): turn a versioned table back into a plain one holding DEFAULT's current rows.
-- Refuses while versions other than DEFAULT have changes in it (they would be
-- lost) unless forced; see tgsis.disable_versioning_rel.
CREATE FUNCTION tgsis.disable_versioning(p_table text, p_force boolean DEFAULT false)
RETURNS bigint
LANGUAGE plpgsql
VOLATILE
AS $$
BEGIN
    RETURN tgsis.disable_versioning_rel(tgsis.resolve_table(p_table), p_force);
END
$$;

COMMENT ON FUNCTION tgsis.disable_versioning(text, boolean) IS
    'make a versioned table plain again with the rows DEFAULT sees (refused while other versions changed it, unless p_force); restores dropped constraints; returns the row versions removed';
