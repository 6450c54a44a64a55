-- tgsis.diff_table(table, a, b, a_revision, b_revision): the objects whose rows of one versioned table differ
-- between two versions (or revisions). tgsis.diff_versions is this over every versioned table; a client that
-- shows progress calls it table by table inside one REPEATABLE READ transaction, which sees the same rows.
-- Per object: rows added (seen in b only), removed (in a only) and changed
-- (same row key, other values). Rows both sides see as the same row version
-- are skipped without reading them twice; rows that are different row
-- versions with equal values (e.g. copied by a merge) are not differences.
-- Objects are named by their keys' canonical text (tgsis.object_key_sql);
-- rows are compared as jsonb with floats written exactly, whatever the
-- session's extra_float_digits (with 0 or less, values differing in the
-- last digits would compare equal).
CREATE FUNCTION tgsis.diff_table(
    p_table      regclass,
    p_a          text,
    p_b          text,
    p_a_revision integer DEFAULT NULL,
    p_b_revision integer DEFAULT NULL)
RETURNS TABLE (objectclass text, objectkey text, shortname text, added bigint, removed bigint, changed bigint)
LANGUAGE plpgsql
STABLE
SET extra_float_digits = 1
AS $$
DECLARE
    v_a    integer[] := tgsis.revision_set(tgsis.version_id(p_a), p_a_revision);
    v_b    integer[] := tgsis.revision_set(tgsis.version_id(p_b), p_b_revision);
    v_t    tgsis.versioned_tables := tgsis.versioned_table(p_table);
    v_keys text;
BEGIN
    SELECT string_agg(format('%I', k), ', ' ORDER BY o) INTO v_keys FROM unnest(v_t.keycolumns) WITH ORDINALITY AS u(k, o);
    RETURN QUERY EXECUTE format(
        'WITH a AS (SELECT %1$s, %7$s AS obj, to_jsonb(v.*) - ''revision'' - ''lastrevs'' - ''revclosed'' AS r
                      FROM %3$s v
                     WHERE v.revision = ANY ($1) AND NOT (v.lastrevs && $1)
                       AND NOT (v.revision = ANY ($2) AND NOT (v.lastrevs && $2))),
              b AS (SELECT %1$s, %7$s AS obj, to_jsonb(v.*) - ''revision'' - ''lastrevs'' - ''revclosed'' AS r
                      FROM %3$s v
                     WHERE v.revision = ANY ($2) AND NOT (v.lastrevs && $2)
                       AND NOT (v.revision = ANY ($1) AND NOT (v.lastrevs && $1)))
         SELECT %5$L::text, coalesce(a.obj, b.obj), %6$L::text,
                count(*) FILTER (WHERE a.r IS NULL), count(*) FILTER (WHERE b.r IS NULL),
                count(*) FILTER (WHERE a.r IS NOT NULL AND b.r IS NOT NULL)
           FROM a FULL JOIN b USING (%1$s)
          WHERE a.r IS DISTINCT FROM b.r
          GROUP BY 2 ORDER BY 2',
        v_keys, v_t.objectkeyfield, tgsis.storage_rows(v_t), NULL, v_t.objectclass, v_t.shortname,
        tgsis.object_key_text_sql(v_t, 'v'))
      USING v_a, v_b;
END
$$;

COMMENT ON FUNCTION tgsis.diff_table(regclass, text, text, integer, integer) IS
    'objects whose rows of one versioned table (given as its view) differ from version a (at a revision) to version b: rows added, removed and changed (by row key and values); TG200 if the table is not versioned';
