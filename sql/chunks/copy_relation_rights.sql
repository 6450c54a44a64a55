-- tgsis.copy_relation_rights(from, to): give a new relation the grants, row-level security and policies of another.
-- The chunk storage takes the rights of what it replaces: a chunk table those
-- of the row table's storage (tgsis.create_chunk_table), a partitioned chunk
-- table those of the chunk table it replaces (tgsis.partition_chunk_storage),
-- so that the same roles reach the same objects' rows. One copy of the
-- catalog walk (grants other than the owner's, with their grant option; row
-- level security enabled; each policy with its roles, expressions and
-- comment) for both. FORCE ROW LEVEL SECURITY is the caller's decision (a
-- chunk table's owner writes through it). Runs with the caller's rights
-- (tgsis's owner, who owns both).
CREATE FUNCTION tgsis.copy_relation_rights(p_from regclass, p_to regclass)
RETURNS void
LANGUAGE plpgsql
VOLATILE
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_acl record;
    v_pol record;
BEGIN
    FOR v_acl IN SELECT a.grantee, a.privilege_type, a.is_grantable
                   FROM pg_class c, aclexplode(c.relacl) AS a
                  WHERE c.oid = p_from AND a.grantee <> c.relowner LOOP
        EXECUTE format('GRANT %s ON %s TO %s%s', v_acl.privilege_type, p_to,
                       CASE WHEN v_acl.grantee = 0 THEN 'PUBLIC' ELSE quote_ident(pg_get_userbyid(v_acl.grantee)) END,
                       CASE WHEN v_acl.is_grantable THEN ' WITH GRANT OPTION' ELSE '' END);
    END LOOP;
    IF (SELECT c.relrowsecurity FROM pg_class c WHERE c.oid = p_from) THEN
        EXECUTE format('ALTER TABLE %s ENABLE ROW LEVEL SECURITY', p_to);
    END IF;
    FOR v_pol IN SELECT p.oid, p.polname, p.polpermissive, p.polcmd, p.polroles,
                        pg_get_expr(p.polqual, p.polrelid) AS qual, pg_get_expr(p.polwithcheck, p.polrelid) AS withcheck
                   FROM pg_policy p WHERE p.polrelid = p_from ORDER BY p.polname LOOP
        EXECUTE format('CREATE POLICY %I ON %s AS %s FOR %s TO %s%s%s', v_pol.polname, p_to,
                       CASE WHEN v_pol.polpermissive THEN 'PERMISSIVE' ELSE 'RESTRICTIVE' END,
                       CASE v_pol.polcmd WHEN 'r' THEN 'SELECT' WHEN 'a' THEN 'INSERT' WHEN 'w' THEN 'UPDATE'
                                         WHEN 'd' THEN 'DELETE' ELSE 'ALL' END,
                       (SELECT string_agg(CASE WHEN r = 0 THEN 'PUBLIC' ELSE quote_ident(pg_get_userbyid(r)) END, ', ')
                          FROM unnest(v_pol.polroles) AS r),
                       CASE WHEN v_pol.qual IS NOT NULL THEN format(' USING (%s)', v_pol.qual) ELSE '' END,
                       CASE WHEN v_pol.withcheck IS NOT NULL THEN format(' WITH CHECK (%s)', v_pol.withcheck) ELSE '' END);
        EXECUTE format('COMMENT ON POLICY %I ON %s IS %L', v_pol.polname, p_to, obj_description(v_pol.oid, 'pg_policy'));
    END LOOP;
END
$$;

REVOKE ALL ON FUNCTION tgsis.copy_relation_rights(regclass, regclass) FROM PUBLIC;

COMMENT ON FUNCTION tgsis.copy_relation_rights(regclass, regclass) IS
    'grant a new relation what another grants (other than to its owner, grant options kept), enable row-level security when the other has it, and copy its policies with their comments; called by tgsis.create_chunk_table, tgsis.swap_into_hash_partitions and tgsis.store_class_in_rows';
