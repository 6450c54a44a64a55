-- tgsis.check_merge_table_write(table, privilege, geoid): refuse (42501) a psql merge's write of a versioned table's rows the calling role may not write through its view.
-- The psql merge of a surface at instants (tgsis.merge_instants_by_slice)
-- writes the storage through tgsis.storage_run, as the table owner's runner:
-- the view's rights, which the Python merge meets (it writes through the
-- views: tgsis.db._state_write), do not hold there by themselves. Asked
-- before each kind of write of a table (DELETE: rows closed or removed,
-- INSERT: rows written, UPDATE: a row changed in place), it refuses as
-- PostgreSQL refuses the Python merge's statement: a role the DBA took
-- INSERT, UPDATE or DELETE on a class's property view from does not get those
-- rows written by merging (tgsis.check_class_write answers for the class's
-- feature table only).
CREATE FUNCTION tgsis.check_merge_table_write(p_table tgsis.versioned_tables, p_privilege text, p_geoid bigint)
RETURNS void
LANGUAGE plpgsql
STABLE
SET search_path = pg_catalog, pg_temp
AS $$
BEGIN
    IF NOT has_table_privilege(tgsis.calling_role(), format('%I.%I', p_table.schemaname, p_table.tablename)::regclass,
                               p_privilege) THEN
        RAISE EXCEPTION 'role % may not % rows of %.%: merging feature % writes its parent''s edits of them into the version',
                quote_ident(tgsis.calling_role()), p_privilege, quote_ident(p_table.schemaname), quote_ident(p_table.tablename),
                p_geoid
            USING ERRCODE = 'insufficient_privilege',
                  HINT = format('a DBA may run: GRANT %s ON %I.%I TO %I; else tgsis.resolve_conflict solves it as a whole object (parent, child or manual)',
                                p_privilege, p_table.schemaname, p_table.tablename, tgsis.calling_role());
    END IF;
END
$$;

REVOKE ALL ON FUNCTION tgsis.check_merge_table_write(tgsis.versioned_tables, text, bigint) FROM PUBLIC;

COMMENT ON FUNCTION tgsis.check_merge_table_write(tgsis.versioned_tables, text, bigint) IS
    'refuse (42501) a psql merge''s write (INSERT, UPDATE or DELETE) of a versioned table''s rows the calling role may not write through the table''s view, as PostgreSQL refuses the Python merge''s statement';
