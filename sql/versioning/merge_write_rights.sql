-- tgsis.merge_write_rights(version, geoid, feature columns, how, what): the rights of a psql merge that writes a feature's merged state into the version first.
-- The psql merges that write before they merge (tgsis.merge_mesh_by_region,
-- by region; tgsis.merge_instants_by_slice, instant by instant) ask what the
-- Python merge's own writes are asked: the right to write in the version
-- (TG002), to change the feature's class (42501, tgsis.check_class_write),
-- and to UPDATE the feature-row columns whose parent's edits the merge brings
-- (42501, as the class's view refuses the Python client's UPDATE of them).
-- One function for both, so that the two merges cannot come to ask
-- different rights. p_how and p_what word the message ('by region', 'mesh').
CREATE FUNCTION tgsis.merge_write_rights(p_version text, p_geoid bigint, p_fcols text[], p_how text, p_what text)
RETURNS void
LANGUAGE plpgsql
STABLE
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_class tgsis.catalog;
    v_why   text;
BEGIN
    IF NOT tgsis.has_version_privilege(p_version, 'write') THEN
        RAISE EXCEPTION 'role % may not write in version %: merging feature % % writes the merged % into the version first, then merges it',
                quote_ident(tgsis.calling_role()), quote_literal(p_version), p_geoid, p_how, p_what
            USING ERRCODE = 'TG002',
                  HINT = format('the owner or a tgsis_admin can run SELECT tgsis.grant_version(%L, ''write'', %L); else tgsis.resolve_conflict solves it as a whole object (parent, child or manual)',
                                p_version, tgsis.calling_role());
    END IF;
    PERFORM tgsis.check_class_write(ARRAY[p_geoid], 'UPDATE, DELETE');
    IF p_fcols IS NULL THEN
        RETURN;
    END IF;
    -- the parent's edits of the feature row: the columns written, as the Python client's UPDATE of the class's
    -- view needs them (a role granted UPDATE on some columns only)
    SELECT c.* INTO v_class FROM tgsis.catalog c WHERE c.classname = tgsis.class_of_geoid(p_geoid);
    SELECT string_agg(quote_ident(u.c), ', ' ORDER BY u.o) INTO v_why
      FROM unnest(p_fcols) WITH ORDINALITY AS u(c, o)
     WHERE NOT has_column_privilege(tgsis.calling_role(), format('%I.%I', v_class.schemaname, v_class.featuretable)::regclass,
                                    u.c, 'UPDATE');
    IF v_why IS NOT NULL THEN
        RAISE EXCEPTION 'role % may not change the properties % of feature % of class %: merging it % brings its parent''s edits of them into the version',
                quote_ident(tgsis.calling_role()), v_why, p_geoid, quote_literal(v_class.classname), p_how
            USING ERRCODE = 'insufficient_privilege',
                  HINT = format('a DBA may run: GRANT UPDATE ON %I.%I TO %I; else tgsis.resolve_conflict solves it as a whole object (parent, child or manual)',
                                v_class.schemaname, v_class.featuretable, tgsis.calling_role());
    END IF;
END
$$;

COMMENT ON FUNCTION tgsis.merge_write_rights(text, bigint, text[], text, text) IS
    'the rights a psql merge that writes a feature''s merged state into the version first asks (tgsis.merge_mesh_by_region, tgsis.merge_instants_by_slice): to write in the version (TG002), to change the class (42501), to UPDATE the feature-row columns whose parent''s edits it brings (42501)';

REVOKE ALL ON FUNCTION tgsis.merge_write_rights(text, bigint, text[], text, text) FROM PUBLIC;
