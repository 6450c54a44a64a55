-- tgsis.create_version(name, parent): a new child version; returns its working revision.
-- Hand-out order (observable, part of the contract): the child's initrevision
-- is the parent's working revision; then the parent gets a new revision; then
-- the child gets its first one.
-- p_base bases the child on an older, frozen revision of the parent instead
-- (a conflicting check-in's child starts from the state the check-out saw,
-- so that its edit and the parent's later ones meet in find_conflicts): then
-- initrevision := p_base, the child sees what that revision saw, and the
-- parent, whose later changes are in later revisions already, gets no new
-- revision. Only the parent's own revisions since its base qualify (those
-- find_conflicts and merge compare with: an older one, from before a merge
-- or refresh re-based the parent, or a revision of an ancestor, would hide
-- changes from the conflict check); p_base = the working revision is the
-- default behaviour.
CREATE FUNCTION tgsis.create_version(p_name text, p_parent text DEFAULT 'DEFAULT', p_description text DEFAULT NULL,
                                     p_base integer DEFAULT NULL)
RETURNS integer
LANGUAGE plpgsql
VOLATILE
SECURITY DEFINER
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_parent     tgsis.versions;
    v_child_rev  integer;
    v_child_id   integer;
    v_constraint text;
    v_base       integer;
    v_baseset    integer[];
BEGIN
    PERFORM tgsis.check_version_name(p_name);
    PERFORM tgsis.require_version_privilege(tgsis.version_id(p_parent), 'create', 'create a child of');
    -- waits for writers of the parent's working revision (write_revision share-locks it)
    SELECT * INTO v_parent FROM tgsis.versions WHERE name = p_parent FOR UPDATE;
    IF NOT FOUND THEN
        -- deleted (or merged away) by the transaction this one waited for: without
        -- this check the new version would get a NULL parent and a NULL-violation
        RAISE EXCEPTION 'version % does not exist', quote_literal(p_parent)
            USING ERRCODE = 'TG200', DETAIL = 'It was deleted while this create_version waited for it.';
    END IF;
    IF EXISTS (SELECT FROM tgsis.versions WHERE name = p_name) THEN
        RAISE EXCEPTION 'version % exists already', quote_literal(p_name)
            USING ERRCODE = 'TG201', HINT = 'choose another name, or tgsis.delete_version it first';
    END IF;

    IF p_base IS NULL OR p_base = v_parent.workingrevision THEN
        v_base := v_parent.workingrevision;
        v_baseset := v_parent.workingset;
        PERFORM tgsis.next_working_revision(v_parent.versionid);
    ELSE
        -- the parent's row lock keeps a merge or refresh from re-basing it meanwhile. The base
        -- must see all the parent sees now but the parent's own later revisions: those are what
        -- find_conflicts and merge_version read as the parent's side (after a refresh the parent
        -- also sees ancestors' revisions the base did not, which no conflict check would show)
        SELECT r.revision, r.visibleset INTO v_base, v_baseset FROM tgsis.revisions r
         WHERE r.revision = p_base AND r.versionid = v_parent.versionid AND r.visibleset IS NOT NULL
           AND r.visibleset <@ v_parent.workingset
           AND NOT EXISTS (SELECT FROM unnest(v_parent.workingset) AS w(rev)
                            WHERE w.rev <> ALL (r.visibleset)
                              AND NOT (w.rev > p_base AND EXISTS (SELECT FROM tgsis.revisions o
                                                                   WHERE o.revision = w.rev
                                                                     AND o.versionid = v_parent.versionid)));
        IF NOT FOUND THEN
            RAISE EXCEPTION 'revision % is not a frozen revision of version % since its base', p_base, quote_literal(p_parent)
                USING ERRCODE = 'TG200',
                      DETAIL = format('A child can be based on the working revision of %L or on one of its own frozen '
                                      'revisions since it was last merged or refreshed; revision %s %s.', p_parent, p_base,
                                      CASE WHEN NOT EXISTS (SELECT FROM tgsis.revisions r WHERE r.revision = p_base)
                                           THEN 'does not exist (never handed out, or removed by compress_versions or delete_version)'
                                           WHEN EXISTS (SELECT FROM tgsis.revisions r WHERE r.revision = p_base AND r.versionid <> v_parent.versionid)
                                           THEN 'belongs to version ' || (SELECT v.name FROM tgsis.revisions r JOIN tgsis.versions v USING (versionid) WHERE r.revision = p_base)
                                           ELSE 'is from before a merge or refresh re-based it' END),
                      HINT = 'pass p_base => NULL to base the child on the parent''s working revision';
        END IF;
    END IF;

    v_child_rev := nextval('tgsis.revision_seq');
    BEGIN
        INSERT INTO tgsis.versions (name, parentid, initrevision, workingrevision, workingset, owner, description)
        VALUES (p_name, v_parent.versionid, v_base, v_child_rev, v_baseset || v_child_rev,
                tgsis.calling_role(), p_description)
        RETURNING versionid INTO v_child_id;
    EXCEPTION WHEN unique_violation THEN
        GET STACKED DIAGNOSTICS v_constraint = CONSTRAINT_NAME;
        IF v_constraint IS DISTINCT FROM 'versions_name_key' THEN
            RAISE;
        END IF;
        -- a concurrent create_version of the same name under another parent (it
        -- locked that parent, not ours, so the check above could not see it yet):
        -- the unique index waited for it; say so as the check above would have
        RAISE EXCEPTION 'version % exists already', quote_literal(p_name)
            USING ERRCODE = 'TG201', HINT = 'choose another name, or tgsis.delete_version it first',
                  DETAIL = 'It was created by a concurrent transaction.';
    END;
    INSERT INTO tgsis.revisions (revision, versionid, created_by) VALUES (v_child_rev, v_child_id, tgsis.calling_role());
    RETURN v_child_rev;
END
$$;

COMMENT ON FUNCTION tgsis.create_version(text, text, text, integer) IS
    'create a child version of p_parent (default DEFAULT): initrevision := parent''s working revision, then a new revision for the parent, then one for the child; with p_base (a frozen revision of the parent since its base) the child is based on that revision and the parent gets none; returns the child''s working revision';
