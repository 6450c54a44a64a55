-- tgsis.conflict_rows(version, objectclass, objectkey): both sides' rows of a conflicting object, for psql users.
-- side 'child' is what the version sees, 'parent' what the parent sees now;
-- rows equal on both sides are left out. The key is read in the key
-- column's type with the session's settings (tgsis.canonical_object_keys);
-- rows are compared as jsonb with floats written exactly.
CREATE FUNCTION tgsis.conflict_rows(p_version text, p_objectclass text, p_objectkey text)
RETURNS TABLE (shortname text, side text, rowkey jsonb, "row" jsonb)
LANGUAGE plpgsql
STABLE
SET extra_float_digits = 1
AS $$
DECLARE
    v_version tgsis.versions;
    v_parent  integer[];
    v_t       tgsis.versioned_tables;
    v_key     text;
BEGIN
    SELECT * INTO v_version FROM tgsis.versions WHERE versionid = tgsis.version_id(p_version);
    PERFORM tgsis.check_object_class(p_objectclass);
    SELECT workingset INTO v_parent FROM tgsis.versions WHERE versionid = v_version.parentid;
    v_key := (tgsis.canonical_object_keys(p_objectclass, ARRAY[p_objectkey]))[1];
    FOR v_t IN SELECT * FROM tgsis.versioned_tables WHERE objectclass = p_objectclass ORDER BY iudorder, shortname LOOP
        RETURN QUERY EXECUTE format(
            'WITH rows AS (
                 SELECT s.side, to_jsonb(v.*) - ''revision'' - ''lastrevs'' - ''revclosed'' AS r, v.revision
                   FROM %s v, (VALUES (''child'', $2), (''parent'', $3)) AS s(side, revs)
                  WHERE v.%I = $1::%s AND v.revision = ANY (s.revs) AND NOT (v.lastrevs && s.revs))
             SELECT %L::text, a.side, (SELECT jsonb_object_agg(key, a.r -> key) FROM unnest($4::text[]) AS key), a.r
               FROM rows a
              WHERE NOT EXISTS (SELECT FROM rows b WHERE b.side <> a.side AND b.r = a.r)
              ORDER BY 3, 2',
            tgsis.storage_rows(v_t), v_t.objectkeyfield, tgsis.object_key_type(v_t), v_t.shortname)
          USING v_key, v_version.workingset, v_parent, v_t.keycolumns;
    END LOOP;
END
$$;

COMMENT ON FUNCTION tgsis.conflict_rows(text, text, text) IS
    'rows of an object that differ between a version (side child) and its parent (side parent), per table, as jsonb with their row key';
