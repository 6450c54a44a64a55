-- tgsis.create_revision_indexes(schema, table, object key column): the indexes of <table>_ver that find row versions by revision.
-- Merges, refreshes and the reads of a merge by region ask "which rows of
-- these objects were written or closed in these revisions": rows with
-- revision in a set, or closed (revclosed) with lastrevs meeting it. Two
-- indexes answer it by a BitmapOr instead of a scan of the objects' rows:
-- * a BRIN on revision: rows are appended in revision order, so page ranges
--   hold few revisions; an insert into the table's last, unsummarized range
--   costs nothing (VACUUM, autovacuum with autosummarize, summarize them);
-- * a btree on the object key of closed rows only (WHERE revclosed): no
--   upload writes a closed row, so uploads do not pay for it; its rows are
--   those closed by edits.
-- A btree on revision would cost every upload a third more, and one on the
-- cells' vertex columns double it (docs/performance.md, the merge section).
-- Model 1's cell tables (tgsis.point, segment, trgl, tetra) get a third, a
-- BRIN on geoid and the vertex columns (vrtxid1..k), model 2's triangles
-- (tgsis.times_trgl) on geoid, times and vrtxid1..3, model 3's (tgsis.d4dtrgl)
-- on geoid, timem and nodeid1..3 (ids repeat at each instant or topology
-- period): geoid because vertex ids
-- are local to their geometry (0..n-1), so every object holds the ids of a
-- change and a BRIN on the vertex columns alone matched ranges of every
-- object (the planner then read all the object's cells by its key instead).
-- The merges by region ask "which
-- cells stand on these vertices" (the one-ring of the change), and a
-- mesh's cells are stored near the cells that share their vertices (files
-- and meshers number them so; uploads keep their order), so a few page
-- ranges hold them. Ranges of 32 pages (a cell found rechecks a few
-- thousand rows). It costs uploads nothing measurable (an insert of 2M
-- triangles 1.00-1.07x); it is not autosummarized: a large upload's ranges
-- overflow autovacuum's queue of work items, which logs each one it drops,
-- and the insert-driven autovacuum after the upload summarizes them (a range
-- not yet summarized is read whole, so results never depend on it).
-- Searched by spans of vertex ids (BETWEEN), not by an = ANY of the ids: a
-- BRIN is searched once per value of an = ANY (tgsis.mesh_merge_work,
-- tgsis.db._merge_states).
-- A model table stored in chunks (issue 40, tgsis.stored_in_chunks) has no
-- <table>_ver: its chunk table got the first two, on the chunk versions,
-- from tgsis.create_chunk_table, and nothing is done (the cells' vertex
-- BRIN has no column to index there: vertex ids are inside arrays).
-- Idempotent (an index of the same kind already there is kept); called by
-- tgsis.enable_versioning_rel and by the upgrade for tables versioned before.
-- Runs with the caller's rights: the caller acts as the storage's owner.
CREATE FUNCTION tgsis.create_revision_indexes(p_schema text, p_table text, p_keyfield text)
RETURNS void
LANGUAGE plpgsql
VOLATILE
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_rel regclass;
BEGIN
    IF tgsis.stored_in_chunks(p_schema, p_table) THEN
        RETURN;
    END IF;
    v_rel := format('%I.%I', p_schema, p_table || '_ver')::regclass;
    IF NOT EXISTS (SELECT FROM pg_index i JOIN pg_class c ON c.oid = i.indexrelid JOIN pg_am a ON a.oid = c.relam
                    WHERE i.indrelid = v_rel AND a.amname = 'brin'
                      AND i.indkey[0] = (SELECT attnum FROM pg_attribute WHERE attrelid = v_rel AND attname = 'revision')) THEN
        EXECUTE format('CREATE INDEX ON %s USING brin (revision) WITH (autosummarize = on)', v_rel);
    END IF;
    IF NOT EXISTS (SELECT FROM pg_index i
                    WHERE i.indrelid = v_rel AND i.indpred IS NOT NULL
                      AND pg_get_expr(i.indpred, i.indrelid) = 'revclosed') THEN
        EXECUTE format('CREATE INDEX ON %s (%I) WHERE revclosed', v_rel, p_keyfield);
    END IF;
    IF p_schema = 'tgsis' AND p_table IN ('point', 'segment', 'trgl', 'tetra', 'times_trgl', 'd4dtrgl')
       AND NOT EXISTS (SELECT FROM pg_index i JOIN pg_class c ON c.oid = i.indexrelid JOIN pg_am a ON a.oid = c.relam
                        WHERE i.indrelid = v_rel AND a.amname = 'brin'
                          AND (SELECT attnum FROM pg_attribute
                                WHERE attrelid = v_rel AND attname IN ('vrtxid1', 'nodeid1')) = ANY (i.indkey::int2[])) THEN
        -- (model 2's triangles also by their instant, model 3's by their topology period: ids repeat in each)
        EXECUTE format('CREATE INDEX ON %s USING brin (geoid, %s) WITH (pages_per_range = 32)', v_rel,
                       (SELECT string_agg(quote_ident(a.attname), ', ' ORDER BY a.attnum) FROM pg_attribute a
                         WHERE a.attrelid = v_rel AND NOT a.attisdropped
                           AND (a.attname ~ '^(vrtxid|nodeid)[0-9]+$' OR a.attname IN ('times', 'timem'))));
    END IF;
END
$$;

COMMENT ON FUNCTION tgsis.create_revision_indexes(text, text, text) IS
    'create the indexes of <table>_ver that find row versions written or closed in given revisions: a BRIN on revision and a btree on the object key of closed rows (WHERE revclosed); on the cell tables of models 1, 2 and 3 also a BRIN on geoid, the instant or period (times, timem) and the vertex columns (the cells of an object on given vertices); idempotent; nothing for a model table stored in chunks (its chunk table has its own)';
