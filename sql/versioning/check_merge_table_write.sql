-- tgsis.check_merge_table_write(table, privilege, geoid, storage): refuse (42501) a psql merge's write of a versioned table's rows the calling role may not make.
-- The psql merges of temporal surfaces (tgsis.merge_instants_by_slice,
-- tgsis.merge_periods_by_slice)
-- writes the storage through tgsis.storage_run, as the table owner's runner:
-- the rights the Python merge meets (tgsis.db._state_write) do not hold
-- there by themselves. Asked before each kind of write of a table, on the
-- relation the Python merge's statement writes: the view (DELETE: rows
-- closed or removed; the per-instant property rows' INSERT, UPDATE,
-- DELETE), or with p_storage the storage itself (INSERT of new row
-- versions, which the Python client COPYs there); refused as PostgreSQL
-- refuses the Python merge's statement: a role the DBA took a right on a
-- class's property view from does not get those rows written by merging
-- (tgsis.check_class_write answers for the class's feature table only).
-- Also asked for SELECT on the per-instant property view, which the Python merge reads.
CREATE FUNCTION tgsis.check_merge_table_write(p_table tgsis.versioned_tables, p_privilege text, p_geoid bigint,
                                              p_storage boolean DEFAULT false)
RETURNS void
LANGUAGE plpgsql
STABLE
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_relation text := CASE WHEN p_storage THEN tgsis.storage_table(p_table.schemaname, p_table.tablename)
                            ELSE format('%I.%I', p_table.schemaname, p_table.tablename) END;
BEGIN
    IF NOT has_table_privilege(tgsis.calling_role(), v_relation::regclass, p_privilege) THEN
        RAISE EXCEPTION 'role % may not % rows of %: merging feature % writes its parent''s edits of them into the version',
                quote_ident(tgsis.calling_role()), p_privilege, v_relation, p_geoid
            USING ERRCODE = 'insufficient_privilege',
                  HINT = format('a DBA may run: GRANT %s ON %s TO %I; else tgsis.resolve_conflict solves it as a whole object (parent, child or manual)',
                                p_privilege, v_relation, tgsis.calling_role());
    END IF;
END
$$;

REVOKE ALL ON FUNCTION tgsis.check_merge_table_write(tgsis.versioned_tables, text, bigint, boolean) FROM PUBLIC;

COMMENT ON FUNCTION tgsis.check_merge_table_write(tgsis.versioned_tables, text, bigint, boolean) IS
    'refuse (42501) a psql merge''s write (INSERT, UPDATE or DELETE) of a versioned table''s rows the calling role may not make through the relation the Python merge writes (the table''s view, or with p_storage its storage), as PostgreSQL refuses the Python merge''s statement';
