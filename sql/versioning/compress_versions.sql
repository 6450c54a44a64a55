-- tgsis.compress_versions(dry_run): remove the revisions, and the row versions, no version, named revision or child can reach any more; returns what it removed.
-- Kept revisions: every version's working revision, every named revision,
-- every version's base (initrevision), and what the next merge or
-- find_conflicts of a version reads: its own working revisions and its
-- parent's revisions since its base. Each kept revision, and each working
-- set, goes on seeing exactly what it saw. Then:
--   rows:        row versions that no kept set sees go, except those closed
--                in a revision a conflict check reads (tgsis.conflicts
--                fingerprints them: a solution must not fall back to unsolved);
--   lastrevs:    entries in no kept set go (no set that exists or can be made
--                from them holds them: they hide nothing), again except in
--                rows a conflict check reads;
--   revisions:   the others go (goto_revision refuses them with TG200);
--   set entries: their numbers go from the kept sets once no row version
--                mentions them (numbers still on rows stay, as plain labels;
--                0 always stays).
-- One transaction: every version row is locked (writers, merges and new
-- revisions wait), the _ver tables are locked against writes. p_dry_run
-- reports the same figures and changes nothing (it blocks no writer).
-- Returns one row per (what, name) with something removed: what is 'rows'
-- or 'lastrevs' (name: schema.table), 'revisions' or 'set entries' (name:
-- the version).
CREATE FUNCTION tgsis.compress_versions(p_dry_run boolean DEFAULT false)
RETURNS TABLE (what text, name text, removed bigint)
LANGUAGE plpgsql
VOLATILE
SECURITY DEFINER
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_dry     boolean := coalesce(p_dry_run, false);
    v_checked integer[];  -- revisions whose changes merge and find_conflicts read
    v_keep    integer[];  -- revisions kept
    v_sets    text[];     -- the revision sets that stay viewable (integer[] as text)
    v_seen    integer[];  -- every revision in one of them
    v_loose   integer[];  -- numbers in kept sets that are not kept revisions
    v_unused  integer[];  -- those that no row version mentions any more
    v_used    integer[];
    v_found   integer[];
    v_t       tgsis.versioned_tables;
    v_ver     text;
    -- a row version stays when a kept set sees it, or when it was closed in a
    -- revision a conflict check reads ($1 sets, $2 their revisions, $3 v_checked)
    v_with    CONSTANT text := 'WITH sets AS MATERIALIZED (SELECT s::integer[] AS revs FROM unnest($1::text[]) AS u(s)) ';
    v_kept    CONSTANT text := '(v.lastrevs && $3 OR (v.revision = ANY ($2) AND (NOT v.revclosed OR EXISTS (
                                   SELECT FROM sets WHERE v.revision = ANY (sets.revs) AND NOT (v.lastrevs && sets.revs)))))';
    v_trim    CONSTANT text := 'NOT (v.lastrevs <@ $2) AND NOT (v.lastrevs && $3)';
BEGIN
    -- writers share-lock their version (tgsis.write_revision); merge, refresh,
    -- create_version, save_revision and delete_version lock it for update
    IF v_dry THEN
        PERFORM FROM tgsis.versions v ORDER BY v.versionid FOR SHARE;
    ELSE
        PERFORM FROM tgsis.versions v ORDER BY v.versionid FOR UPDATE;
    END IF;
    LOCK TABLE tgsis.versioned_tables IN SHARE MODE;  -- no table is versioned or unversioned meanwhile

    SELECT coalesce(array_agg(DISTINCT c.r ORDER BY c.r), '{}') INTO v_checked FROM (
        SELECT unnest(tgsis.own_working_revisions(v.versionid)) FROM tgsis.versions v WHERE v.parentid IS NOT NULL
        UNION ALL
        SELECT r.revision FROM tgsis.versions v JOIN tgsis.revisions r ON r.versionid = v.parentid
         WHERE r.revision > v.initrevision) AS c(r);
    SELECT array_agg(DISTINCT k.r ORDER BY k.r) INTO v_keep FROM (
        SELECT v.workingrevision FROM tgsis.versions v
        UNION ALL
        SELECT v.initrevision FROM tgsis.versions v WHERE v.initrevision IS NOT NULL
        UNION ALL
        SELECT r.revision FROM tgsis.revisions r WHERE r.name IS NOT NULL
        UNION ALL
        SELECT unnest(v_checked)) AS k(r);
    SELECT array_agg(DISTINCT s.revs::text) INTO v_sets FROM (
        SELECT v.workingset FROM tgsis.versions v
        UNION ALL
        SELECT r.visibleset FROM tgsis.revisions r WHERE r.revision = ANY (v_keep) AND r.visibleset IS NOT NULL) AS s(revs);
    v_seen := ARRAY(SELECT DISTINCT u.r FROM unnest(v_sets) AS s(revs), unnest(s.revs::integer[]) AS u(r) ORDER BY 1);
    -- 0 stays in every set whatever happens to its revision: enable_versioning labels a table's existing rows with it
    v_loose := ARRAY(SELECT u.r FROM unnest(v_seen) AS u(r) WHERE u.r <> ALL (v_keep) AND u.r <> 0 ORDER BY 1);
    v_used := '{}';

    FOR v_t IN SELECT * FROM tgsis.versioned_tables t ORDER BY t.schemaname, t.tablename LOOP
        v_ver := tgsis.storage_table(v_t.schemaname, v_t.tablename);  -- <table>_ver, or the chunk versions of tgsis.<table>_chunk
        name := format('%s.%s', v_t.schemaname, v_t.tablename);
        -- every statement on storage as its owner (tgsis.storage_run): $1 the kept sets, $2 their
        -- revisions, $3 the checked revisions, $5 the loose numbers
        IF NOT v_dry THEN
            EXECUTE format('LOCK TABLE %s IN EXCLUSIVE MODE', v_ver);  -- reads go on, writes wait (runs no code of the table's)
        END IF;

        what := 'rows';
        IF v_dry THEN
            SELECT r[1]::bigint INTO removed FROM tgsis.storage_run(v_t, false,
                v_with || format('SELECT ARRAY[count(*)::text] FROM %s v WHERE NOT %s', v_ver, v_kept),
                v_sets, v_seen, v_checked) AS r;
        ELSE
            SELECT r[1]::bigint INTO removed FROM tgsis.storage_run(v_t, true,
                v_with || format('DELETE FROM %s v WHERE NOT %s', v_ver, v_kept), v_sets, v_seen, v_checked) AS r;
        END IF;
        IF removed > 0 THEN
            RETURN NEXT;
        END IF;

        what := 'lastrevs';
        SELECT r[1]::bigint INTO removed FROM tgsis.storage_run(v_t, false, v_with || format(
            'SELECT ARRAY[coalesce(sum((SELECT count(*) FROM unnest(v.lastrevs) AS l(r) WHERE l.r <> ALL ($2))), 0)::text]
               FROM %s v WHERE %s AND %s', v_ver, v_trim, v_kept), v_sets, v_seen, v_checked) AS r;
        IF NOT v_dry AND removed > 0 THEN
            PERFORM FROM tgsis.storage_run(v_t, true, format(
                'UPDATE %s v SET lastrevs = ARRAY(SELECT l.r FROM unnest(v.lastrevs) WITH ORDINALITY AS l(r, o)
                                                  WHERE l.r = ANY ($2) ORDER BY l.o)
                  WHERE %s', v_ver, v_trim), v_sets, v_seen, v_checked);
        END IF;
        IF removed > 0 THEN
            RETURN NEXT;
        END IF;

        -- loose numbers still on a (remaining) row version stay in the sets
        IF cardinality(v_loose) > 0 THEN
            SELECT r::integer[] INTO v_found FROM tgsis.storage_run(v_t, false, v_with || format(
                'SELECT coalesce(array_agg(DISTINCT u.r::text), ''{}'') FROM %s v, unnest(v.revision || v.lastrevs) AS u(r)
                  WHERE u.r = ANY ($5) AND %s', v_ver, v_kept), v_sets, v_seen, v_checked, NULL, v_loose::bigint[]) AS r;
            v_used := v_used || v_found;
        END IF;
    END LOOP;
    v_unused := ARRAY(SELECT u.r FROM unnest(v_loose) AS u(r) WHERE u.r <> ALL (v_used) ORDER BY 1);

    RETURN QUERY
        SELECT 'revisions', v.name, count(*)
          FROM tgsis.versions v JOIN tgsis.revisions r ON r.versionid = v.versionid
         WHERE r.revision <> ALL (v_keep)
         GROUP BY v.versionid, v.name ORDER BY v.versionid;
    RETURN QUERY
        SELECT 'set entries', v.name, n.removed
          FROM tgsis.versions v,
               LATERAL (SELECT (SELECT count(*) FROM unnest(v.workingset) AS w(r) WHERE w.r = ANY (v_unused))
                             + (SELECT count(*) FROM tgsis.revisions k, unnest(k.visibleset) AS s(r)
                                 WHERE k.versionid = v.versionid AND k.revision = ANY (v_keep) AND s.r = ANY (v_unused))
                          AS removed) AS n
         WHERE n.removed > 0
         ORDER BY v.versionid;
    IF v_dry THEN
        RETURN;
    END IF;

    DELETE FROM tgsis.revisions r WHERE r.revision <> ALL (v_keep);
    -- the notes of changed objects go with their revisions: nothing asks about those any more
    DELETE FROM tgsis.revision_objects o WHERE o.revision <> ALL (v_keep);
    IF cardinality(v_unused) > 0 THEN
        UPDATE tgsis.versions v
           SET workingset = ARRAY(SELECT u.r FROM unnest(v.workingset) WITH ORDINALITY AS u(r, o)
                                   WHERE u.r <> ALL (v_unused) ORDER BY u.o)
         WHERE v.workingset && v_unused;
        UPDATE tgsis.revisions r
           SET visibleset = ARRAY(SELECT u.r FROM unnest(r.visibleset) WITH ORDINALITY AS u(r, o)
                                   WHERE u.r <> ALL (v_unused) ORDER BY u.o)
         WHERE r.visibleset && v_unused;
    END IF;
END
$$;

REVOKE ALL ON FUNCTION tgsis.compress_versions(boolean) FROM PUBLIC;

COMMENT ON FUNCTION tgsis.compress_versions(boolean) IS
    'remove the revisions no version, named revision or child can reach (kept: working, named, bases, and what merges and conflict checks read), the row versions only they saw and lastrevs entries that hide nothing; never changes what a version or kept revision sees, nor conflicts; p_dry_run only reports; rows (what, name, removed)';
