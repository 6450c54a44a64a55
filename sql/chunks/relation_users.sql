-- tgsis.relation_users(relation, kept_views, kept_triggers): what uses a table that replacing it would break or lose, named.
-- tgsis.partition_chunk_storage and tgsis.partition_row_storage replace a
-- storage table by a partitioned one of the same definition
-- (tgsis.swap_into_hash_partitions). What the swap makes again is allowed:
-- the table's own checks and policies, its defaults, the views given (made
-- again over the new table by their own definitions) and the triggers given
-- by name (tgsis's own, made again by the caller). Anything else that refers
-- to it — a user's view, a foreign key, a function body, a user's trigger
-- (LIKE copies none, so it would be dropped silently) — is returned as one
-- text naming each, for the caller's TG202; NULL when nothing is in the way.
-- One query for both storages, so that they refuse the same things.
CREATE FUNCTION tgsis.relation_users(p_relation regclass, p_kept_views regclass[], p_kept_triggers name[])
RETURNS text
LANGUAGE sql
STABLE
SET search_path = pg_catalog, pg_temp
AS $$
    SELECT string_agg(DISTINCT u, ', ') FROM (
        SELECT CASE WHEN d.classid = 'pg_rewrite'::regclass
                    THEN (SELECT 'view ' || r.ev_class::regclass::text FROM pg_rewrite r WHERE r.oid = d.objid)
                    ELSE pg_describe_object(d.classid, d.objid, 0) END
          FROM pg_depend d
         WHERE d.refclassid = 'pg_class'::regclass AND d.refobjid = p_relation AND d.deptype = 'n'
           AND NOT (d.classid = 'pg_rewrite'::regclass
                    AND EXISTS (SELECT FROM pg_rewrite r WHERE r.oid = d.objid AND r.ev_class = ANY (p_kept_views)))
           AND NOT (d.classid = 'pg_constraint'::regclass        -- the table's own checks name its columns
                    AND EXISTS (SELECT FROM pg_constraint c WHERE c.oid = d.objid AND c.conrelid = p_relation))
           AND NOT (d.classid = 'pg_policy'::regclass            -- its own policies (copied)
                    AND EXISTS (SELECT FROM pg_policy p WHERE p.oid = d.objid AND p.polrelid = p_relation))
           AND d.classid NOT IN ('pg_trigger'::regclass, 'pg_attrdef'::regclass)
        UNION ALL
        SELECT format('trigger %s on %s', t.tgname, t.tgrelid::regclass)
          FROM pg_trigger t
         WHERE NOT t.tgisinternal AND t.tgrelid = p_relation AND NOT t.tgname = ANY (p_kept_triggers)
    ) AS s(u)
$$;

REVOKE ALL ON FUNCTION tgsis.relation_users(regclass, regclass[], name[]) FROM PUBLIC;

COMMENT ON FUNCTION tgsis.relation_users(regclass, regclass[], name[]) IS
    'the objects that use a table and that replacing it by tgsis.swap_into_hash_partitions would break or lose (users'' views, foreign keys, function bodies, triggers other than p_kept_triggers), named in one text; its own checks, policies, defaults and the views p_kept_views (made again) are not counted; NULL when none';
