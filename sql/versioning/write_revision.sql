-- tgsis.write_revision(): the version, revision and revision set a write of this session uses, or TG301/TG002 if it may not write.
-- Every write path calls it: the statement and row triggers of versioned
-- views, the statement triggers of storage, the client's bulk paths. It
-- share-locks the version's row until the transaction ends, so that
-- create_version, save_revision, merge and refresh (which lock it for update)
-- never hand the working revision on while a writer is still labelling rows
-- with it; the row is locked only when the calling role holds the write
-- right, so that nobody else can take that lock and keep it (a reader
-- holding it in an open transaction would stop them all).
-- The row triggers call it once per row rather than trusting the check of
-- their statement trigger: the session's version is a setting, which a
-- function called by the statement itself could change between rows. So
-- the usual case is one query: the right (tgsis_admin, the version's owner,
-- a grant, an ancestor's owner: tgsis.holds_version_privilege's rule, in
-- its cheapest order) is part of the locking query's condition.
CREATE FUNCTION tgsis.write_revision(OUT versionid integer, OUT revision integer, OUT revisions integer[])
LANGUAGE plpgsql
VOLATILE
SECURITY DEFINER
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_name    text := coalesce(nullif(current_setting('tgsis.version', true), ''), 'DEFAULT');
    v_viewing text := nullif(btrim(current_setting('tgsis.revision', true)), '');
    v_role    name := tgsis.calling_role();
BEGIN
    SELECT v.versionid, v.workingrevision, v.workingset INTO versionid, revision, revisions
      FROM tgsis.versions v
     WHERE v.name = v_name
       AND (pg_has_role(v_role, 'tgsis_admin', 'USAGE')
            OR v.owner = v_role
            OR EXISTS (SELECT FROM tgsis.version_privileges p LEFT JOIN pg_roles r ON r.rolname = p.grantee
                        WHERE p.versionid = v.versionid AND p.privilege = 'write'
                          AND (p.grantee = 'public' OR (r.oid IS NOT NULL AND pg_has_role(v_role, r.oid, 'USAGE'))))
            OR tgsis.is_version_owner(v.versionid, v_role))
       FOR SHARE OF v;
    IF NOT FOUND THEN
        -- no such version, or no right (require_version_privilege says which right, whose, and the grant)
        PERFORM tgsis.require_version_privilege(tgsis.version_id(v_name), 'write', 'write in');
        -- it had the right after all: deleted, or given the right, by a transaction this one waited for
        RAISE EXCEPTION 'version % changed while this write waited for it', quote_literal(v_name)
            USING ERRCODE = 'serialization_failure', HINT = 'retry the transaction';
    END IF;
    IF v_viewing IS NOT NULL THEN
        PERFORM tgsis.check_writable_revision(v_name, revision);  -- TG301 (the error ends the lock with the transaction)
    END IF;
END
$$;

COMMENT ON FUNCTION tgsis.write_revision() IS
    'version id, working revision and working set for a write in the session''s version, share-locking the version until commit when the calling role holds the write right; TG002 without it, TG301 while an older revision is viewed (the error ends the lock with the transaction)';
