-- tgsis.conflict_discards(version, objectclass, objectkey): what each solution of a conflicting object throws away.
-- Until merges are three-way, a solution takes one side's whole object:
-- 'child' (and 'manual', which takes the version's object too) discards the
-- parent's edits, 'parent' the version's, 'base' both sides' (a row each). An edit is a row key whose row
-- differs between the common base (what the version was based on: its
-- working set without its own revisions) and that side; it is discarded when
-- the chosen side's row differs from the edited one (an edit both sides made
-- alike is kept). Per object, solution and table: rows the other side added
-- (dropped), removed (brought back) and changed (reverted or overwritten),
-- and the column values among them (added or removed rows count all their
-- values). Only tables with something discarded are listed. The objects'
-- rows are read by key with the caller's rights (tgsis.storage_run), only in
-- tables either side noted a change in since the base (tgsis.revision_objects,
-- which tgsis.changed_objects reads too); row versions the base and both
-- sides see alike are left out before they are compared (of a model table
-- stored in chunks, the slots of a changed chunk the three sets see alike too:
-- tgsis.storage_changed_rows, so the cost is sized by the change). Row versions are compared as jsonb, whose
-- floats are their float8 text: extra_float_digits is pinned (a session's 0 or less printed 15 digits or fewer,
-- so an edit in the 16th or 17th digit looked like no edit, and two instants of one such text one row key).
CREATE FUNCTION tgsis.conflict_discards(p_version text, p_objectclass text DEFAULT NULL, p_objectkey text DEFAULT NULL)
RETURNS TABLE (objectclass text, objectkey text, solution text, discarded text, shortname text, tablename text,
               description text, rows_added bigint, rows_removed bigint, rows_changed bigint, values_changed bigint)
LANGUAGE plpgsql
VOLATILE
SET extra_float_digits = 1
AS $$
DECLARE
    v_version tgsis.versions;
    v_parent  integer[];
    v_base    integer[];
    v_changed integer[];
    v_differ  integer[];
    v_t       tgsis.versioned_tables;
    v_class   text;
    v_keys    text[];
    v_rowkey  text;
    v_desc    text;
BEGIN
    SELECT * INTO v_version FROM tgsis.versions WHERE versionid = tgsis.version_id(p_version);
    IF v_version.parentid IS NULL THEN
        RAISE EXCEPTION 'version DEFAULT has no parent to conflict with' USING ERRCODE = 'TG100';
    END IF;
    IF p_objectclass IS NOT NULL THEN
        PERFORM tgsis.check_object_class(p_objectclass);
        -- a key given as text names the object by its canonical text, whatever the session's settings
        p_objectkey := (tgsis.canonical_object_keys(p_objectclass, ARRAY[p_objectkey]))[1];
    ELSIF p_objectkey IS NOT NULL THEN
        RAISE EXCEPTION 'an object key (%) needs its object class', left(p_objectkey, 80) USING ERRCODE = 'TG100',
            HINT = 'call tgsis.conflict_discards(version, objectclass, objectkey)';
    END IF;
    SELECT workingset INTO v_parent FROM tgsis.versions WHERE versionid = v_version.parentid;
    v_base := ARRAY(SELECT r FROM unnest(v_version.workingset) AS r
                    EXCEPT SELECT r FROM unnest(tgsis.own_working_revisions(v_version.versionid)) AS r ORDER BY 1);
    -- the revisions either side changed something in since the base (never revision 0, which the base holds)
    v_changed := ARRAY(SELECT r FROM unnest(v_version.workingset || v_parent) AS r
                       EXCEPT SELECT r FROM unnest(v_base) AS r ORDER BY 1);
    -- the revisions not in all three sets: a row version seen by some of them and not all was written in
    -- one of these or closed in one, the form the storage's revision indexes serve
    -- (tgsis.create_revision_indexes)
    v_differ := ARRAY(SELECT r FROM unnest(v_base || v_version.workingset || v_parent) AS r
                      EXCEPT (SELECT r FROM unnest(v_base) AS r
                              INTERSECT SELECT r FROM unnest(v_version.workingset) AS r
                              INTERSECT SELECT r FROM unnest(v_parent) AS r) ORDER BY 1);
    FOR v_class, v_keys IN
        SELECT c.objectclass, array_agg(c.objectkey ORDER BY c.objectkey)
          FROM tgsis.current_conflicts(v_version.versionid) AS c
         WHERE (p_objectclass IS NULL OR c.objectclass = p_objectclass) AND (p_objectkey IS NULL OR c.objectkey = p_objectkey)
         GROUP BY 1 ORDER BY 1
    LOOP
        FOR v_t IN SELECT t.* FROM tgsis.versioned_tables t WHERE t.objectclass = v_class ORDER BY t.iudorder, t.shortname LOOP
            -- a table neither side wrote in since the base (tgsis.revision_objects) has nothing to lose (any
            -- object's note will do: a key's text is not compared, so no session setting can hide one)
            CONTINUE WHEN NOT EXISTS (SELECT FROM tgsis.revision_objects o
                                       WHERE o.revision = ANY (v_changed) AND o.schemaname = v_t.schemaname
                                         AND o.tablename = v_t.tablename);
            SELECT string_agg(format('v.%I', k), ', ' ORDER BY o) INTO v_rowkey
              FROM unnest(v_t.keycolumns) WITH ORDINALITY AS u(k, o);
            v_desc := coalesce(
                (SELECT m.description FROM tgsis.model_tables m
                  WHERE v_t.schemaname = 'tgsis' AND m.tablename = v_t.tablename),
                (SELECT CASE c.kind WHEN 'feature' THEN format('a feature of class %s', c.classname)
                                    WHEN 'instant' THEN format('the properties of a feature of class %s at an instant', c.classname)
                                    ELSE format('the properties of a vertex or cell of class %s', c.classname) END
                   FROM tgsis.class_tables c WHERE c.schemaname = v_t.schemaname AND c.tablename = v_t.tablename),
                format('a row of %I.%I', v_t.schemaname, v_t.tablename));
            -- $2 base, $3 the version, $5 the parent (bigint[]: the slots storage_run has). Only row
            -- versions not seen alike by all three sets are read: the others are the same row everywhere.
            RETURN QUERY
            SELECT v_t.objectclass, r[1], r[2], r[3], v_t.shortname, format('%I.%I', v_t.schemaname, v_t.tablename),
                   v_desc, r[4]::bigint, r[5]::bigint, r[6]::bigint, r[7]::bigint
              FROM tgsis.storage_run(v_t, false, format(
                'WITH seen AS (
                     SELECT %7$s AS obj, jsonb_build_array(%2$s) AS rowkey,
                            to_jsonb(v.*) - ''revision'' - ''lastrevs'' - ''revclosed'' AS r,
                            v.revision = ANY ($2) AND NOT (v.lastrevs && $2) AS in_base,
                            v.revision = ANY ($3) AND NOT (v.lastrevs && $3) AS in_child,
                            v.revision = ANY ($5::integer[]) AND NOT (v.lastrevs && $5::integer[]) AS in_parent
                       FROM %3$s v
                      WHERE v.%1$I = ANY ($1::%5$s[])
                        -- not a row version all three see: rows of the object that nobody changed cost a test,
                        -- not a jsonb. (All three sets hold its revision: a base revision of the version, merged
                        -- into the parent as a copy, is not in the parent set; a row of it was taken for one all
                        -- three see, and the copy in the parent counted as a row the parent added.)
                        AND NOT (v.revision = ANY ($2) AND v.revision = ANY ($3) AND v.revision = ANY ($5::integer[])
                                 AND NOT (v.lastrevs && $2) AND NOT (v.lastrevs && $3)
                                 AND NOT (v.lastrevs && $5::integer[]))
                        AND (v.revision = ANY (%8$L::integer[]) OR (v.revclosed AND v.lastrevs && %8$L::integer[]))),
                 keyed AS (
                     SELECT obj, (array_agg(r) FILTER (WHERE in_base))[1] AS b,
                            (array_agg(r) FILTER (WHERE in_child))[1] AS c,
                            (array_agg(r) FILTER (WHERE in_parent))[1] AS p
                       FROM seen
                      WHERE (in_base OR in_child OR in_parent) AND NOT (in_base AND in_child AND in_parent)
                      GROUP BY obj, rowkey),
                 -- choosing a side: the other side''s edits (o differs from the base) that the kept rows (k) lose
                 lost AS (
                     SELECT x.obj, x.solution, x.discarded, x.b, x.o, x.k
                       FROM keyed,
                            LATERAL (VALUES (obj, ''child'', ''parent'', b, p, c), (obj, ''parent'', ''child'', b, c, p),
                                            (obj, ''base'', ''parent'', b, p, b), (obj, ''base'', ''child'', b, c, b))
                                    AS x (obj, solution, discarded, b, o, k)
                      WHERE x.o IS DISTINCT FROM x.b AND x.k IS DISTINCT FROM x.o)
                 SELECT ARRAY[obj, solution, discarded,
                              count(*) FILTER (WHERE b IS NULL)::text,
                              count(*) FILTER (WHERE o IS NULL)::text,
                              count(*) FILTER (WHERE b IS NOT NULL AND o IS NOT NULL)::text,
                              sum((SELECT count(*) FROM jsonb_object_keys(coalesce(b, ''{}'') || coalesce(o, ''{}'')) AS col
                                    WHERE col <> ALL (%6$L::text[])
                                      AND (o -> col) IS DISTINCT FROM (b -> col)
                                      AND (k -> col) IS DISTINCT FROM (o -> col)))::text]
                   FROM lost
                  GROUP BY obj, solution, discarded
                  ORDER BY obj, solution',
                v_t.objectkeyfield, v_rowkey,
                -- (a model table stored in chunks: only the slots whose values or presence differ between the
                -- three sets, tgsis.storage_changed_rows; the other slots of a changed chunk are alike everywhere)
                CASE WHEN v_t.schemaname = 'tgsis' AND v_t.objectkeyfield = 'geoid'
                     THEN tgsis.storage_changed_rows(v_t.schemaname, v_t.tablename, v_keys::bigint[], v_base,
                                                     v_version.workingset, v_parent)
                     ELSE tgsis.storage_rows(v_t) END,
                NULL, tgsis.object_key_type(v_t),
                v_t.keycolumns || v_t.objectkeyfield,
                tgsis.object_key_text_sql(v_t, 'v'),  -- the key's canonical text, as the conflicts name it
                v_differ),
                p_1 => v_keys, p_2 => v_base, p_3 => v_version.workingset, p_5 => v_parent::bigint[]) AS r;
        END LOOP;
    END LOOP;
END
$$;

COMMENT ON FUNCTION tgsis.conflict_discards(text, text, text) IS
    'per conflicting object of a version (optionally one class or object), solution (child: the parent''s edits are lost, as with manual; parent: the version''s; base: both sides'') and table: the other side''s edits since the common base that the solution discards: rows added, removed, changed, and the column values among them';
