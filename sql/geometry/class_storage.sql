-- tgsis.class_storage(table): where the rows of a feature class's table (or of tgsis.geometry) are stored.
-- Once versioned, the table is a view over <table>_ver (tgsis.enable_versioning);
-- before, the table holds its rows. Decided by what the relation is, not by
-- whether a relation named <table>_ver exists: anyone who may create tables in
-- the class's schema could make one, and a class may itself be called
-- <name>_ver. (tgsis.storage_table says the same from tgsis.versioned_tables,
-- which the per-class rights' functions, listed above it, cannot call.)
CREATE FUNCTION tgsis.class_storage(p_table regclass)
RETURNS regclass
LANGUAGE sql
STABLE
PARALLEL SAFE
SET search_path = pg_catalog, pg_temp
AS $$
    SELECT CASE WHEN c.relkind = 'v' THEN to_regclass(format('%I.%I', n.nspname, c.relname || '_ver')) ELSE c.oid::regclass END
      FROM pg_catalog.pg_class c JOIN pg_catalog.pg_namespace n ON n.oid = c.relnamespace
     WHERE c.oid = p_table
$$;

COMMENT ON FUNCTION tgsis.class_storage(regclass) IS
    'the relation storing a table''s rows: <table>_ver when the table is a (versioned) view, else the table itself';
