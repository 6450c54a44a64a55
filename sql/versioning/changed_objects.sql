-- tgsis.changed_objects(revisions): objects with rows written or closed in any of the given revisions, per table.
-- One scan of each versioned table's storage.
CREATE FUNCTION tgsis.changed_objects(p_revisions integer[])
RETURNS TABLE (objectclass text, objectkey text, shortname text, mark text)
LANGUAGE plpgsql
VOLATILE
AS $$
DECLARE
    v_t tgsis.versioned_tables;
BEGIN
    IF cardinality(p_revisions) = 0 THEN
        RETURN;
    END IF;
    FOR v_t IN SELECT * FROM tgsis.versioned_tables ORDER BY objectclass, iudorder, shortname LOOP
        -- mark: a fingerprint of the object's changed row versions, so that
        -- any later write to them (even in the same revision) shows; the row
        -- as record_out writes it (v::text would call a cast the row type's
        -- owner may have created); read as the storage's owner from definer code
        RETURN QUERY SELECT v_t.objectclass, r[1], v_t.shortname, r[2] FROM tgsis.storage_run(v_t, false, format(
            'SELECT ARRAY[v.%I::text, md5(string_agg(pg_catalog.record_out(v.*)::text, ''|'' ORDER BY %s, v.revision))]
               FROM %I.%I v
              WHERE v.revision = ANY ($2) OR v.lastrevs && $2
              GROUP BY v.%I',
            v_t.objectkeyfield,
            (SELECT string_agg(format('v.%I', k), ', ' ORDER BY o) FROM unnest(v_t.keycolumns) WITH ORDINALITY AS u(k, o)),
            v_t.schemaname, v_t.tablename || '_ver', v_t.objectkeyfield), p_2 => p_revisions) AS r;
    END LOOP;
END
$$;

COMMENT ON FUNCTION tgsis.changed_objects(integer[]) IS
    'per versioned table, the objects (class, key as text) with row versions written or closed in the given revisions, and a fingerprint (md5) of those row versions';
