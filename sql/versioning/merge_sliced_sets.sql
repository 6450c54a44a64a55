-- tgsis.merge_sliced_sets(version, geoid, time model, what, how): the checks and the three revision sets a psql merge of a temporal surface starts with.
-- Shared by tgsis.merge_instants_by_slice (model 2, 'INSTANTS') and
-- tgsis.merge_periods_by_slice (model 3, 'EVOLVING'): TG100 for a feature of
-- another time model, 42501 for a role that may not read its class;
-- p_refused true (the Python merge leaves it unsolved too: deleted on one
-- side, attributes changed on both, tgsis.object_merge_refusal) or the
-- feature's class, the base (the version at its initial revision), the
-- parent's and the version's working sets, and p_since: the revisions whose
-- rows some set sees otherwise than another (written or closed since the
-- version was based). p_what and p_how word the messages ('a surface at
-- instants (model 2)', 'instant by instant').
CREATE FUNCTION tgsis.merge_sliced_sets(p_version text, p_geoid bigint, p_timemodel text, p_what text, p_how text,
                                        OUT p_refused boolean, OUT p_class tgsis.catalog, OUT p_versionid integer,
                                        OUT p_base integer[], OUT p_parentset integer[], OUT p_versionset integer[],
                                        OUT p_since integer[])
LANGUAGE plpgsql
VOLATILE
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_version tgsis.versions;
BEGIN
    SELECT * INTO v_version FROM tgsis.versions WHERE versionid = tgsis.version_id(p_version);
    SELECT v.workingset INTO p_parentset FROM tgsis.versions v WHERE v.versionid = v_version.parentid;
    SELECT c.* INTO p_class FROM tgsis.catalog c WHERE c.classname = tgsis.class_of_geoid(p_geoid);
    IF p_class.timemodel IS DISTINCT FROM p_timemodel THEN
        RAISE EXCEPTION 'feature % is not %', p_geoid, p_what
            USING ERRCODE = 'TG100', HINT = format('SELECT tgsis.merge_version(%L) merges it as its model merges', p_version);
    END IF;
    IF p_geoid IN (SELECT tgsis.class_denied_geoids('SELECT')) THEN
        RAISE EXCEPTION 'role % may not read feature % (its class): it cannot be merged %',
                quote_ident(tgsis.calling_role()), p_geoid, p_how
            USING ERRCODE = '42501', HINT = 'the class''s owner can GRANT SELECT on its feature table';
    END IF;
    p_refused := tgsis.object_merge_refusal(p_version, p_geoid) IS NOT NULL;
    IF p_refused THEN
        RETURN;
    END IF;
    p_versionid := v_version.versionid;
    p_base := tgsis.revision_set(v_version.versionid, v_version.initrevision);
    p_versionset := v_version.workingset;
    p_since := ARRAY(SELECT r FROM unnest(p_base || p_parentset || p_versionset) AS r
                     EXCEPT SELECT r FROM unnest(p_base) AS r WHERE r = ANY (p_parentset) AND r = ANY (p_versionset)
                     ORDER BY 1);
END
$$;

-- internal to the psql merges, not executable by PUBLIC (tests/test_function_grants.py)
REVOKE ALL ON FUNCTION tgsis.merge_sliced_sets(text, bigint, text, text, text) FROM PUBLIC;

COMMENT ON FUNCTION tgsis.merge_sliced_sets(text, bigint, text, text, text) IS
    'the checks (time model, the right to read the class, the object-level refusals) and the revision sets (base, parent, version, changed since) a psql merge of a temporal surface starts with';
