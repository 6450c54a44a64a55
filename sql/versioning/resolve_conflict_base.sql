-- tgsis.resolve_conflict_base(version, objectclass, objectkey, key): the base solution of a conflicting object, written into the version.
-- Called by tgsis.resolve_conflict (which checked the solution, the right to
-- write in the version, and stored the conflicts of now) for 'base': the
-- object as the version was based on it — its working set without its own
-- revisions, what tgsis.conflict_discards calls the base — is made what the
-- version sees (tgsis.copy_object_state: only rows that differ are closed or
-- copied, attributes included), so that 'manual' then takes it. Refused
-- before anything is written: an object not in conflict (TG200); a mesh
-- whose stored regions include one that merges by itself (TG307: base
-- would drop the edit there, which the merge by region keeps; solve the
-- conflicting regions with base instead); a feature of a class the role may
-- not change (42501); an object another version locked (TG303). A NOTICE
-- says what of the version's edits it discards (tgsis.conflict_discards,
-- solution base); resolve_conflict's own NOTICE, once 'manual' is recorded,
-- says what of the parent's (the version holds the base: every parent edit).
-- The conflicts are stored again afterwards: the version's marks changed.
-- Returns the rows written.
-- It writes as a write through the views would, and takes what they take:
-- the write right on the version (checked again here: it is a definer
-- function, and only tgsis's owner may call it), the version's row share-locked
-- (tgsis.write_revision's lock: a save, merge or refresh waits, so the
-- working revision it labels rows with is not frozen or handed on under it),
-- the object's write lock in the version (tgsis.object_write_lock's: a view
-- writer of it in flight is waited for, and the state read after), READ
-- COMMITTED (TG300 otherwise: an older snapshot would miss what it waited
-- for), and per table of a role's own (not tgsis's model tables, which
-- tgsis.check_class_write guards per class) the right the change needs on it:
-- DELETE for the version's added rows, INSERT for its removed ones, UPDATE
-- for its changed ones (42501 otherwise).
CREATE FUNCTION tgsis.resolve_conflict_base(p_version text, p_objectclass text, p_objectkey text, p_key text)
RETURNS bigint
LANGUAGE plpgsql
VOLATILE
SECURITY DEFINER
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_version tgsis.versions;
    v_base    integer[];
    v_kept    text;
    v_said    text;
    v_written bigint;
    v_denied  text;
BEGIN
    PERFORM tgsis.require_read_committed('the base solution of a conflict');
    PERFORM tgsis.require_version_privilege(tgsis.version_id(p_version), 'write', 'resolve conflicts of');
    -- write_revision's lock: no save, merge or refresh hands the working revision on while base writes in it
    SELECT * INTO v_version FROM tgsis.versions WHERE versionid = tgsis.version_id(p_version) FOR SHARE;
    IF NOT FOUND THEN
        RAISE EXCEPTION 'version % does not exist', quote_literal(p_version)
            USING ERRCODE = 'TG200', DETAIL = 'It was removed while the base solution waited for it.';
    END IF;
    -- object_write_lock's locks in that version: writers of the object through the views are waited for
    PERFORM pg_catalog.pg_advisory_xact_lock_shared(tgsis.object_class_lock_key(p_objectclass, v_version.versionid));
    PERFORM pg_catalog.pg_advisory_xact_lock(tgsis.object_lock_key(p_objectclass, p_key, v_version.versionid));
    IF NOT EXISTS (SELECT FROM tgsis.conflicts k WHERE k.versionid = v_version.versionid
                      AND k.objectclass = p_objectclass AND k.objectkey = p_key) THEN
        RAISE EXCEPTION 'object % of class % is not in conflict in version %', quote_literal(p_objectkey),
                quote_literal(p_objectclass), quote_literal(p_version)
            USING ERRCODE = 'TG200', HINT = format('SELECT * FROM tgsis.find_conflicts(%L) lists the conflicts', p_version);
    END IF;
    IF p_objectclass = 'feature' THEN
        -- models 2 and 3 first (the message names the slices): a slice one side alone changed merges by itself
        v_kept := concat_ws('; ', 'the parent''s edits of ' || tgsis.slice_only_edits(p_version, p_key::bigint, 'parent'),
                            'the version''s edits of ' || tgsis.slice_only_edits(p_version, p_key::bigint, 'child'));
        IF v_kept <> '' THEN
            RAISE EXCEPTION 'solution base of object % of class % in version % would drop %, which only that side changed',
                    quote_literal(p_objectkey), quote_literal(p_objectclass), quote_literal(p_version), v_kept
                USING ERRCODE = 'TG307',
                      DETAIL = 'A surface at instants merges instant by instant, an evolving surface geometry instant by geometry instant: a slice only one side changed merges by itself.',
                      HINT = format('tgsis version merge %s merges it slice by slice (tgsis version resolve %s %s base --region N solves its conflicting regions)',
                                    tgsis.shell_quote(p_version), tgsis.shell_quote(p_version), tgsis.shell_quote(p_key));
        END IF;
    END IF;
    -- then a region no side's conflict (model 1, and the regions of a slice both sides changed)
    SELECT string_agg(format('%s (%s)', r.region, CASE r.changed_by WHEN 'child' THEN 'the version''s edit'
                                                                     WHEN 'parent' THEN 'the parent''s edit'
                                                                     ELSE 'both sides'' same edit' END),
                      ', ' ORDER BY r.region) INTO v_kept
      FROM tgsis.conflict_regions r
     WHERE r.versionid = v_version.versionid AND r.objectclass = p_objectclass AND r.objectkey = p_key AND NOT r.conflict;
    IF v_kept IS NOT NULL THEN
        RAISE EXCEPTION 'solution base of object % of class % in version % would drop the edits in regions % that are no conflict',
                quote_literal(p_objectkey), quote_literal(p_objectclass), quote_literal(p_version), v_kept
            USING ERRCODE = 'TG307',
                  DETAIL = 'Those regions merge by themselves: the merge by region keeps their edits.',
                  HINT = format('solve the conflicting regions with SELECT tgsis.resolve_region(%L, %L, %L, region, ''base''); the merge takes the rest by itself',
                                p_version, p_objectclass, p_key);
    END IF;
    IF p_objectclass = 'feature' THEN
        PERFORM tgsis.check_class_write(ARRAY[p_key::bigint], 'UPDATE');
    END IF;
    PERFORM tgsis.check_objects_unlocked(p_objectclass, ARRAY[p_key], v_version.versionid, true);
    -- the rights a write of these changes through the table's view needs (a role's own tables; tgsis's
    -- model tables follow the class's rights: check_class_write above)
    SELECT string_agg(format('%s on %s', d.needed, d.tablename), ', ' ORDER BY d.tablename) INTO v_denied
      FROM (SELECT d.tablename,
                   concat_ws(', ', CASE WHEN d.rows_added > 0 AND NOT has_table_privilege(tgsis.calling_role(), d.tablename, 'DELETE') THEN 'DELETE' END,
                                   CASE WHEN d.rows_removed > 0 AND NOT has_table_privilege(tgsis.calling_role(), d.tablename, 'INSERT') THEN 'INSERT' END,
                                   CASE WHEN d.rows_changed > 0 AND NOT has_table_privilege(tgsis.calling_role(), d.tablename, 'UPDATE') THEN 'UPDATE' END) AS needed
              FROM tgsis.conflict_discards(p_version, p_objectclass, p_key) AS d
              JOIN tgsis.versioned_tables t ON format('%I.%I', t.schemaname, t.tablename) = d.tablename
             WHERE d.solution = 'base' AND d.discarded = 'child' AND t.schemaname <> 'tgsis') AS d
     WHERE d.needed <> '';
    IF v_denied IS NOT NULL THEN
        RAISE EXCEPTION 'role % may not write the base of object % of class % into version %: it lacks %',
                quote_ident(tgsis.calling_role()), quote_literal(p_objectkey), quote_literal(p_objectclass),
                quote_literal(p_version), v_denied
            USING ERRCODE = 'insufficient_privilege',
                  DETAIL = 'base reverts the version''s rows as writes through the tables would: removing its added rows, bringing back its removed ones, changing back its changed ones.',
                  HINT = 'the tables'' owner can GRANT the rights named; or solve the conflict with parent or child';
    END IF;
    -- what of the version's edits it throws away, said before it is gone
    SELECT string_agg(format('%s: %s (%s value%s)', d.shortname,
                             concat_ws(', ', CASE WHEN d.rows_added > 0 THEN d.rows_added || ' added' END,
                                       CASE WHEN d.rows_removed > 0 THEN d.rows_removed || ' removed' END,
                                       CASE WHEN d.rows_changed > 0 THEN d.rows_changed || ' changed' END),
                             d.values_changed, CASE WHEN d.values_changed <> 1 THEN 's' END), '; ' ORDER BY d.shortname)
      INTO v_said
      FROM tgsis.conflict_discards(p_version, p_objectclass, p_key) AS d
     WHERE d.solution = 'base' AND d.discarded = 'child';
    IF v_said IS NOT NULL THEN
        RAISE NOTICE '% % of version % (solution base) written into the version: the version''s edits discarded: %',
            p_objectclass, p_key, quote_literal(p_version), v_said;
    END IF;
    v_base := ARRAY(SELECT r FROM unnest(v_version.workingset) AS r
                    EXCEPT SELECT r FROM unnest(tgsis.own_working_revisions(v_version.versionid)) AS r ORDER BY 1);
    v_written := tgsis.copy_object_state(p_objectclass, ARRAY[p_key], v_base, v_version.workingset,
                                         v_version.workingrevision);
    PERFORM tgsis.find_conflicts(p_version);  -- the version's marks of now, so that manual holds for its new state
    RETURN v_written;
END
$$;

COMMENT ON FUNCTION tgsis.resolve_conflict_base(text, text, text, text) IS
    'the base solution of a conflicting object (tgsis.resolve_conflict calls it): write the object as the version was based on it into the version, after refusing a mesh with regions that merge by themselves and saying what of the version''s edits it discards; returns the rows written';

-- only tgsis.resolve_conflict (owner's code, after its checks) calls it
REVOKE ALL ON FUNCTION tgsis.resolve_conflict_base(text, text, text, text) FROM PUBLIC;
