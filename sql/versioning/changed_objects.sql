-- tgsis.changed_objects(revisions): objects with rows written or closed in any of the given revisions, per table.
-- The candidates are the objects noted in tgsis.revision_objects for those
-- revisions; their rows are read by key (the storage's primary key or its
-- object index) and tested as a scan would test them, so what comes back,
-- and the marks, do not depend on how many notes there are. Tables with no
-- note are not read at all: the cost follows the change, not the database.
-- Revision 0 is never noted: asked about it, each table is scanned.
-- Keys are their canonical text (tgsis.object_key_sql), and the marks are
-- computed with fixed settings: tgsis.conflicts keeps them, and a session
-- of other settings (DateStyle, TimeZone, ...) must compute the same mark
-- for the same rows, or find_conflicts would take a solved conflict for a
-- changed one.
CREATE FUNCTION tgsis.changed_objects(p_revisions integer[])
RETURNS TABLE (objectclass text, objectkey text, shortname text, mark text)
LANGUAGE plpgsql
VOLATILE
SET DateStyle = 'ISO, YMD'
SET TimeZone = 'UTC'
SET IntervalStyle = 'postgres'
SET extra_float_digits = 1
SET bytea_output = 'hex'
SET lc_monetary = 'C'
AS $$
DECLARE
    v_t       tgsis.versioned_tables;
    v_scan    boolean := 0 = ANY (p_revisions);
    v_keys    text[];
    v_where   text;
BEGIN
    IF cardinality(p_revisions) = 0 THEN
        RETURN;
    END IF;
    FOR v_t IN SELECT * FROM tgsis.versioned_tables ORDER BY objectclass, iudorder, shortname LOOP
        -- (a closed row is revclosed: so written, the storage's revision indexes serve it, tgsis.create_revision_indexes)
        v_where := 'v.revision = ANY ($2) OR (v.revclosed AND v.lastrevs && $2)';
        IF NOT v_scan THEN
            v_keys := ARRAY(SELECT DISTINCT o.objectkey FROM tgsis.revision_objects o
                             WHERE o.revision = ANY (p_revisions) AND o.schemaname = v_t.schemaname
                               AND o.tablename = v_t.tablename);
            CONTINUE WHEN cardinality(v_keys) = 0;
            -- keys compared in the column's own type, so that its index serves
            v_where := format('v.%I = ANY ($1::%s[]) AND (%s)', v_t.objectkeyfield, tgsis.object_key_type(v_t), v_where);
        END IF;
        -- mark: a fingerprint of the object's changed row versions, so that
        -- any later write to them (even in the same revision) shows; the row
        -- as record_out writes it (v::text would call a cast the row type's
        -- owner may have created); read as the storage's owner from definer code
        RETURN QUERY SELECT v_t.objectclass, r[1], v_t.shortname, r[2] FROM tgsis.storage_run(v_t, false, format(
            'SELECT ARRAY[%s, md5(string_agg(pg_catalog.record_out(v.*)::text, ''|'' ORDER BY %s, v.revision))]
               FROM %s v
              WHERE %s
              GROUP BY v.%I',
            tgsis.object_key_text_sql(v_t, 'v'),  -- the key's canonical text
            -- (stored versions in the storage's key order: the row key, or (geoid, chunk) for chunk versions)
            (SELECT string_agg(format('v.%I', k), ', ' ORDER BY o) FROM unnest(tgsis.storage_key(v_t)) WITH ORDINALITY AS u(k, o)),
            tgsis.storage_table(v_t.schemaname, v_t.tablename), v_where, v_t.objectkeyfield), p_1 => v_keys, p_2 => p_revisions) AS r;
    END LOOP;
END
$$;

COMMENT ON FUNCTION tgsis.changed_objects(integer[]) IS
    'per versioned table, the objects (class, key as text) with row versions written or closed in the given revisions, and a fingerprint (md5) of those row versions; reads the rows of the objects noted in tgsis.revision_objects';
