-- tgsis.create_version(name, parent): a new child version; returns its working revision.
-- Hand-out order (observable, part of the contract): the child's initrevision
-- is the parent's working revision; then the parent gets a new revision; then
-- the child gets its first one.
CREATE FUNCTION tgsis.create_version(p_name text, p_parent text DEFAULT 'DEFAULT', p_description text DEFAULT NULL)
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

    PERFORM tgsis.next_working_revision(v_parent.versionid);

    v_child_rev := nextval('tgsis.revision_seq');
    BEGIN
        INSERT INTO tgsis.versions (name, parentid, initrevision, workingrevision, workingset, owner, description)
        VALUES (p_name, v_parent.versionid, v_parent.workingrevision, v_child_rev, v_parent.workingset || v_child_rev,
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

COMMENT ON FUNCTION tgsis.create_version(text, text, text) IS
    'create a child version of p_parent (default DEFAULT): initrevision := parent''s working revision, then a new revision for the parent, then one for the child; returns the child''s working revision';
