-- tgsis.checkout_revision(): the frozen revision whose state a check-out reads, freezing the working revision if need be; NULL when nothing can be frozen.
-- Why: a version's working revision stays open for writes, and a write in it
-- is made in place, so the state a check-out saw in it could not be found
-- again once a colleague changed the object. Frozen, it stays stored: a
-- conflicting check-in can base its child version on it (create_version's
-- p_base), so that the two edits meet as a conflict of the normal merge path.
-- In the session's version:
--   viewing an older revision: that revision (frozen already; nothing written);
--   feature versioning off, a read-only transaction, or a role without the
--   write right: NULL, without writing or locking anything (readers check out
--   as before; their check-in cannot take the child path);
--   a REPEATABLE READ or SERIALIZABLE transaction: NULL too, because its
--   snapshot may predate writes the freeze waited for, so what it reads is
--   not what the frozen revision holds;
--   otherwise the working revision is frozen (tgsis.next_working_revision
--   under the version's row lock, which waits for open writers of the version,
--   as create_version and save_revision do) and returned.
-- Costs: one revision per check-out in the version's working set (and in the
-- sets of children created later); compress_versions removes it when no
-- version, name or child needs it, after which such a check-in's child path
-- is refused (TG200 from create_version).
CREATE FUNCTION tgsis.checkout_revision()
RETURNS integer
LANGUAGE plpgsql
VOLATILE
SECURITY DEFINER
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_name    text := tgsis.get_working_version();
    v_viewing integer := tgsis.get_viewing_revision();
    v_version tgsis.versions;
BEGIN
    SELECT * INTO v_version FROM tgsis.versions WHERE name = v_name;
    IF NOT FOUND THEN
        RAISE EXCEPTION 'version % does not exist', quote_literal(v_name)
            USING ERRCODE = 'TG200', HINT = 'SELECT tgsis.goto_version(''DEFAULT'')';
    END IF;
    IF v_viewing IS NOT NULL AND v_viewing <> v_version.workingrevision THEN
        PERFORM tgsis.revision_set(v_version.versionid, v_viewing);  -- TG200 unless in its history
        RETURN v_viewing;
    END IF;
    IF NOT EXISTS (SELECT FROM tgsis.versioned_tables WHERE schemaname = 'tgsis' AND tablename = 'vrtx')
       OR current_setting('transaction_read_only')::boolean
       OR current_setting('transaction_isolation') <> 'read committed'
       OR NOT tgsis.has_version_privilege(v_name, 'write') THEN
        RETURN NULL;
    END IF;
    SELECT * INTO v_version FROM tgsis.versions WHERE versionid = v_version.versionid FOR UPDATE;
    IF NOT FOUND THEN
        RAISE EXCEPTION 'version % does not exist', quote_literal(v_name)
            USING ERRCODE = 'TG200', DETAIL = 'It was deleted while this check-out waited for it.';
    END IF;
    PERFORM tgsis.next_working_revision(v_version.versionid);
    RETURN v_version.workingrevision;
END
$$;

COMMENT ON FUNCTION tgsis.checkout_revision() IS
    'the frozen revision a check-out of the session''s version reads: the viewed older revision, else the working revision, frozen now (a new one starts; waits for open writers of the version); NULL without writing or locking when feature versioning is off, the transaction is read-only or not READ COMMITTED, or the role may not write in the version';
