-- tgsis.swap_object_chunks(table, geoid, chunks, bases): swap chunk versions a client encoded into one object of a chunked model table, for the calling role.
-- The bulk write of a check-in on chunks (docs/storage.md, "Writing an
-- edit"): tgsis.write_object_rows re-aggregates every touched chunk in SQL
-- (3-5 ms a chunk), which a scattered edit pays for nearly every chunk of the
-- object. Here the client read the visible versions of the touched chunks
-- (p_chunks) with their places (p_bases: tableoid:ctid:xmin, NULL where no
-- version was visible), merged its edit into them and encoded the result
-- itself (tgsis._chunks, as the upload does), COPied into the transaction's stage
-- (tgsis.object_chunks_stage); a touched chunk absent from the stage is left
-- without a row. After the checks of tgsis.write_object_rows, for a write that
-- may change stored rows (INSERT and DELETE on the face tgsis.<table>: 42501;
-- the class's write right, tgsis.check_class_write; versioned: READ COMMITTED
-- (TG300), the version's write right and TG301 (tgsis.write_revision), the
-- object not locked by another version (TG303), else TG305; the object's write
-- lock exclusively, tgsis.object_write_lock), every staged chunk is verified as
-- the upload's are (tgsis.chunk_encoding_checks: 23514) and must be of the
-- object and of p_chunks, once each (TG100). The visible versions of p_chunks
-- are then locked in chunk order, and each must still be the one the client
-- based its chunk on (its place, or none visible): else TG300 and nothing is
-- written (a writer changed the chunk between the client's read and this
-- swap: its change would be lost). The write is then the one of
-- tgsis.write_chunk_rows, so that the chunks written are the same bit for bit:
-- a chunk whose content stays the same is not written; else in place when
-- the visible version is the working revision's, otherwise closed (the
-- working revision appended to lastrevs) and inserted anew in it; a chunk
-- left without rows deleted (the working revision's) or closed. A new chunk
-- version that a concurrent writer inserted first: TG300, nothing written.
-- The object is noted as changed (tgsis.record_changed_objects) when a chunk
-- was written. Returns the number of chunks written (a chunk closed and written
-- anew counts once, as tgsis.write_chunk_rows counts); the stage is emptied.
-- A class's property table stored in chunks (tgsis.store_class_in_chunks,
-- named as tgsis.chunk_registry names it: 'public.rock_cellpros') is swapped
-- the same way (docs/storage.md, "The bulk paths of property chunks"), with
-- tgsis.write_property_rows' checks in place of the model tables' class
-- right (the face's grants are the class table's: INSERT and DELETE on the
-- face, 42501), the object's lock as a feature, and what the row definition
-- refuses: a NULL at a present slot of a NOT NULL property (TG100); a class
-- whose row definition has CHECK constraints is refused (TG100, nothing
-- written: tgsis.write_property_rows evaluates them row by row), but for a
-- vector property's own CHECK as the class made it (k values from 1, none
-- NULL), which every 2-D array the encoding checks pass holds.
CREATE FUNCTION tgsis.swap_object_chunks(p_table text, p_geoid bigint, p_chunks bigint[], p_bases text[])
RETURNS bigint
LANGUAGE plpgsql
VOLATILE
SECURITY DEFINER
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_reg      record;
    v_objclass text;
    v_kc       text;
    v_notnull  text[];
    v_colsa    text[];
    v_face     text;
    v_chunk    regclass;
    v_stage    text;
    v_refs     text[];
    v_vals     text[];
    v_keys     text[];
    v_w        integer;
    v_set      integer[];
    v_vis      text := '(c.revision = ANY ($1)) IS TRUE AND NOT (c.lastrevs && $1)';
    v_versioned boolean;
    v_bad      record;
    v_locked   text[];
    v_new      text[];
    v_more     boolean;
    v_moved    bigint;
    v_written  bigint;
    v_missed   bigint;
    v_same     text;
    v_cols     text;
    v_sql      text;
BEGIN
    SELECT * INTO v_reg FROM tgsis.chunk_registry(p_table) r WHERE r.chunkcolumn IS NOT NULL;
    IF NOT FOUND OR NOT tgsis.stored_in_chunks(v_reg.schemaname, v_reg.tablename) THEN
        RAISE EXCEPTION '% is not stored in chunks',
                        CASE WHEN strpos(coalesce(p_table, ''), '.') > 0 THEN p_table ELSE 'tgsis.' || coalesce(quote_ident(p_table), 'NULL') END
            USING ERRCODE = 'TG100',
                  DETAIL = 'tgsis.swap_object_chunks writes the model tables switched to chunks (tgsis.stored_in_chunks) '
                           'and the property tables of classes switched by tgsis.store_class_in_chunks.',
                  HINT = 'write the rows of a table stored as rows through its view or storage';
    END IF;
    PERFORM tgsis.client_chunks_check(p_table, 'swap_object_chunks');  -- TG100: keys, a model table's value columns
    v_objclass := CASE WHEN v_reg.classname IS NULL
                       THEN (SELECT t.objectclass FROM tgsis.model_tables t WHERE t.tablename = v_reg.tablename)
                       ELSE 'feature' END;
    v_kc := v_reg.keycolumn;
    v_stage := format('pg_temp.%I', 'tgsis_object_chunks_'
                                    || CASE WHEN v_reg.classname IS NULL THEN p_table ELSE tgsis.chunk_table_of(p_table)::oid::text END);
    IF to_regclass(v_stage) IS NULL
       OR (SELECT c.relowner FROM pg_class c WHERE c.oid = to_regclass(v_stage))
          <> (SELECT r.oid FROM pg_roles r WHERE r.rolname = current_user) THEN
        RAISE EXCEPTION 'no chunks staged for tgsis.%', quote_ident(p_table)
            USING ERRCODE = 'TG100',
                  DETAIL = 'The chunks are COPied first into the table tgsis.object_chunks_stage makes.',
                  HINT = 'call tgsis.object_chunks_stage, COPY the chunks into its table, then this function';
    END IF;
    IF p_geoid IS NULL OR p_chunks IS NULL OR p_bases IS NULL
       OR coalesce(cardinality(p_chunks), 0) <> coalesce(cardinality(p_bases), 0)
       OR array_position(p_chunks, NULL) IS NOT NULL
       OR EXISTS (SELECT FROM unnest(p_chunks) AS k WHERE k < 0)
       OR (SELECT count(DISTINCT k) FROM unnest(p_chunks) AS k) <> coalesce(cardinality(p_chunks), 0) THEN
        RAISE EXCEPTION 'the chunks to swap into tgsis.% are not given one base each', quote_ident(p_table)
            USING ERRCODE = 'TG100',
                  DETAIL = format('geoid %s; chunks %s; bases %s: each chunk (0 or more, once) with the place of the '
                                  'version it was based on (NULL: none).', coalesce(p_geoid::text, 'NULL'),
                                  coalesce(cardinality(p_chunks)::text, 'NULL'), coalesce(cardinality(p_bases)::text, 'NULL')),
                  HINT = 'give as many bases as chunks';
    END IF;
    v_chunk := tgsis.chunk_table_of(p_table);
    v_face := tgsis.chunk_relation(p_table, '');
    v_keys := ARRAY[p_geoid::text];
    v_refs := ARRAY(SELECT c.name FROM tgsis.chunk_columns(p_table) c WHERE c.role = 'ref' ORDER BY c.colorder);
    v_vals := ARRAY(SELECT c.name FROM tgsis.chunk_columns(p_table) c WHERE c.role IN ('float', 'ref', 'value', 'vector') ORDER BY c.colorder)
              || ARRAY(SELECT r || '_wide' FROM unnest(v_refs) AS r);
    IF cardinality(p_chunks) = 0 THEN
        EXECUTE format('TRUNCATE %s', v_stage);
        RETURN 0;
    END IF;

    -- the rights of a write that may change stored rows (tgsis.write_object_rows'), then the locks
    IF NOT has_table_privilege(tgsis.calling_role(), v_face::regclass, 'INSERT')
       OR NOT has_table_privilege(tgsis.calling_role(), v_face::regclass, 'DELETE') THEN
        RAISE EXCEPTION 'role % may not write %', quote_ident(tgsis.calling_role()), v_face
            USING ERRCODE = 'insufficient_privilege',
                  DETAIL = 'Swapping chunks may add, change and remove rows: it needs INSERT and DELETE on it.',
                  HINT = 'its owner can GRANT INSERT, DELETE on it; or write the rows with tgsis.write_object_rows';
    END IF;
    IF v_reg.classname IS NULL THEN
        PERFORM tgsis.check_class_write(ARRAY[p_geoid], 'UPDATE');
    ELSIF EXISTS (SELECT FROM pg_constraint con WHERE con.conrelid = tgsis.row_shape(p_table) AND con.contype = 'c'
                     AND con.conname <> v_reg.tablename || '_shape_holds_no_rows'
                     -- (a vector property's own CHECK, as the class made it: held by every chunk the encoding checks pass)
                     AND pg_get_expr(con.conbin, con.conrelid) NOT IN (
                             SELECT format('((array_ndims(%1$I) = 1) AND (array_lower(%1$I, 1) = 1) AND (cardinality(%1$I) = %2$s) '
                                           'AND (array_position(%1$I, NULL::%3$s) IS NULL))', c.name, c.size, c.typename)
                               FROM tgsis.chunk_columns(p_table) c WHERE c.role = 'vector')) THEN
        RAISE EXCEPTION '% has CHECK constraints: its chunks are not swapped', v_face
            USING ERRCODE = 'TG100',
                  DETAIL = 'The constraints are evaluated on rows; nothing was written.',
                  HINT = 'write the rows with tgsis.write_property_rows, which checks them';
    END IF;
    v_versioned := EXISTS (SELECT FROM tgsis.versioned_tables t WHERE t.schemaname = v_reg.schemaname AND t.tablename = v_reg.tablename);
    IF v_versioned THEN
        PERFORM tgsis.require_read_committed('a swap of chunk versions of versioned objects');
        PERFORM tgsis.write_revision();  -- TG002, TG301 before any lock is taken
        PERFORM tgsis.check_objects_unlocked(v_objclass, v_keys);
    ELSE
        PERFORM tgsis.plain_write_check(v_reg.schemaname, v_reg.tablename);  -- TG305
    END IF;
    PERFORM tgsis.object_write_lock(v_objclass, v_keys);
    -- the working revision and the set it sees (tgsis.write_chunk_rows')
    IF v_versioned THEN
        IF v_reg.classname IS NULL AND v_objclass = 'feature' AND EXISTS (SELECT FROM tgsis.unversioned_features u WHERE u.geoid = p_geoid) THEN
            v_w := tgsis.unversioned_revision(ARRAY[p_geoid]);  -- TG305, TG300
            v_set := ARRAY[0];
        ELSE
            SELECT w.revision, w.revisions INTO v_w, v_set FROM tgsis.write_revision() AS w;
        END IF;
    ELSE
        v_w := 0;
        v_set := ARRAY[0];
    END IF;

    -- the staged chunks: of this object and of p_chunks, once each, encoded as the upload's are checked
    -- (a class's NOT NULL property: NULL at its holes only, which the encoding checks make NULL; a vector's
    -- 2-D array, whose rows are all NULL or none: k NULLs a hole)
    v_notnull := ARRAY(SELECT CASE WHEN c.role = 'vector'
                                   THEN format('(SELECT count(*) FROM unnest(c.%I) AS e WHERE e IS NULL) = %s * coalesce(cardinality(c.holes), 0)',
                                               c.name, c.size)
                                   ELSE format('coalesce(cardinality(array_positions(c.%I, NULL)), 0) = coalesce(cardinality(c.holes), 0)', c.name) END
                         FROM tgsis.chunk_columns(p_table) c
                        WHERE c.role IN ('value', 'vector') AND EXISTS (SELECT FROM pg_attribute a WHERE a.attrelid = tgsis.row_shape(p_table)
                                                              AND a.attname = c.name AND a.attnotnull)
                        ORDER BY c.colorder);
    EXECUTE format('SELECT c.%3$I AS geoid, c.chunk, count(*) OVER () AS n FROM %1$s c '
                   'WHERE NOT coalesce(c.%3$I = $1 AND c.chunk = ANY ($2) AND %2$s, false) ORDER BY 2 LIMIT 1',
                   v_stage, array_to_string(tgsis.chunk_encoding_checks(p_table), ' AND '), v_kc)
       INTO v_bad USING p_geoid, p_chunks;
    IF v_bad.n IS NOT NULL THEN
        RAISE EXCEPTION 'staged chunk of % is not encoded as its readers read it, or not of the chunks given: object %, chunk %',
                        v_face, v_bad.geoid, v_bad.chunk
            USING ERRCODE = 'check_violation',
                  DETAIL = format('%s staged chunk(s) of another object, not among the %s chunks given, or encoded against '
                                  'the contract (docs/storage.md, "Chunks and the mapping of ids"); nothing was written.',
                                  v_bad.n, cardinality(p_chunks)),
                  HINT = format('write the rows with tgsis.write_object_rows or through the view %s, which encode them', v_face);
    END IF;
    IF cardinality(v_notnull) > 0 THEN
        EXECUTE format('SELECT c.chunk FROM %s c WHERE NOT (%s) ORDER BY c.chunk LIMIT 1', v_stage, array_to_string(v_notnull, ' AND '))
           INTO v_moved;
        IF v_moved IS NOT NULL THEN
            RAISE EXCEPTION 'staged chunk % of % has a NULL value of a NOT NULL property', v_moved, v_face
                USING ERRCODE = 'TG100', DETAIL = 'A NULL is allowed at a hole only there; nothing was written.',
                      HINT = 'give every present row a value of the NOT NULL properties';
        END IF;
    END IF;
    EXECUTE format('SELECT c.chunk FROM %s c GROUP BY c.chunk HAVING count(*) > 1 LIMIT 1', v_stage) INTO v_moved;
    IF v_moved IS NOT NULL THEN
        RAISE EXCEPTION 'chunk % of tgsis.% is staged twice', v_moved, quote_ident(p_table)
            USING ERRCODE = 'TG100', DETAIL = 'Each chunk is staged once, with all its rows; nothing was written.',
                  HINT = 'stage each touched chunk once';
    END IF;

    -- lock the visible versions of p_chunks in chunk order, until every visible one is locked
    v_locked := '{}';
    LOOP
        EXECUTE format('SELECT coalesce(array_agg(l.t), ''{}'') FROM (
                          SELECT c.tableoid::text || '':'' || c.ctid::text AS t FROM %1$s c
                           WHERE c.%3$I = $2 AND c.chunk = ANY ($3) AND %2$s
                             AND c.tableoid::text || '':'' || c.ctid::text <> ALL ($4)
                           ORDER BY c.chunk FOR UPDATE OF c) l', v_chunk, v_vis, v_kc)
           INTO v_new USING v_set, p_geoid, p_chunks, v_locked;
        v_locked := v_locked || v_new;
        EXECUTE format('SELECT EXISTS (SELECT FROM %1$s c WHERE c.%3$I = $2 AND c.chunk = ANY ($3) AND %2$s
                                         AND c.tableoid::text || '':'' || c.ctid::text <> ALL ($4))', v_chunk, v_vis, v_kc)
           INTO v_more USING v_set, p_geoid, p_chunks, v_locked;
        EXIT WHEN NOT v_more;
    END LOOP;
    -- no lost update: each chunk's visible version is still the one the client read (or none still)
    EXECUTE format('SELECT b.chunk, b.base, v.place, count(*) OVER () AS n
                      FROM unnest($3, $4) AS b(chunk, base)
                      LEFT JOIN (SELECT c.chunk, c.tableoid::text || '':'' || c.ctid::text || '':'' || c.xmin::text AS place
                                   FROM %1$s c WHERE c.%3$I = $2 AND c.chunk = ANY ($3) AND %2$s) v ON v.chunk = b.chunk
                     WHERE b.base IS DISTINCT FROM v.place ORDER BY b.chunk LIMIT 1', v_chunk, v_vis, v_kc)
       INTO v_bad USING v_set, p_geoid, p_chunks, p_bases;
    IF v_bad.n IS NOT NULL THEN
        RAISE EXCEPTION 'chunk % of object % in % changed since it was read', v_bad.chunk, p_geoid, v_face
            USING ERRCODE = 'TG300',
                  DETAIL = format('%s of the %s chunks given are no longer the versions the edit was based on (chunk %s: '
                                  'read %s, now %s): another transaction wrote them; nothing was written.',
                                  v_bad.n, cardinality(p_chunks), v_bad.chunk, coalesce(v_bad.base, 'none'),
                                  coalesce(v_bad.place, 'none')),
                  HINT = 'read the chunks again and retry the write';
    END IF;

    -- the write: tgsis.write_chunk_rows' statements, with the staged content as the new one
    v_same := array_to_string(ARRAY['s.holes IS NOT DISTINCT FROM v.holes']
                              || CASE WHEN cardinality(v_refs) > 0 THEN ARRAY['s.vbase IS NOT DISTINCT FROM v.vbase'] ELSE '{}'::text[] END
                              || ARRAY(SELECT format('array_send(s.%1$I) IS NOT DISTINCT FROM array_send(v.%1$I)', c)
                                         FROM unnest(v_vals) AS c), ' AND ');
    v_colsa := ARRAY['holes'] || CASE WHEN cardinality(v_refs) > 0 THEN ARRAY['vbase', 'vtop'] ELSE '{}'::text[] END
               || ARRAY(SELECT quote_ident(c) FROM unnest(v_vals) AS c);
    v_cols := array_to_string(v_colsa, ', ');
    v_sql := format($q$
WITH e AS (
    SELECT b.chunk, v.vtoid, v.vtid, v.revision AS vrev, s.chunk IS NOT NULL AS filled,
           (v.vtid IS NOT NULL AND s.chunk IS NOT NULL AND %1$s) AS unchanged
      FROM unnest($3) AS b(chunk)
      LEFT JOIN (SELECT c.tableoid AS vtoid, c.ctid AS vtid, c.* FROM %2$s c WHERE c.%8$I = $2 AND c.chunk = ANY ($3) AND %3$s) v
        ON v.chunk = b.chunk
      LEFT JOIN %4$s s ON s.chunk = b.chunk
), upd AS (
    UPDATE %2$s c SET %7$s FROM e JOIN %4$s s ON s.chunk = e.chunk
     WHERE c.tableoid = e.vtoid AND c.ctid = e.vtid AND e.vrev = $5 AND e.filled AND NOT e.unchanged
    RETURNING c.chunk
), del AS (
    DELETE FROM %2$s c USING e
     WHERE c.tableoid = e.vtoid AND c.ctid = e.vtid AND e.vrev = $5 AND NOT e.filled
    RETURNING c.chunk
), cls AS (
    UPDATE %2$s c SET lastrevs = c.lastrevs || $5 FROM e
     WHERE c.tableoid = e.vtoid AND c.ctid = e.vtid AND e.vrev <> $5 AND NOT e.unchanged
    RETURNING c.chunk
), fresh AS (
    SELECT e.chunk FROM e WHERE e.filled AND NOT (e.vtid IS NOT NULL AND (e.vrev = $5 OR e.unchanged))
), ins AS (
    INSERT INTO %2$s (%8$I, chunk, revision, %5$s)
    SELECT $2, s.chunk, $5, %6$s FROM %4$s s JOIN fresh f ON f.chunk = s.chunk
     ORDER BY s.chunk
    ON CONFLICT DO NOTHING
    RETURNING chunk
)
SELECT (SELECT count(*) FROM (SELECT * FROM upd UNION SELECT * FROM del UNION SELECT * FROM cls UNION SELECT * FROM ins) w),
       (SELECT count(*) FROM fresh) - (SELECT count(*) FROM ins)
$q$, v_same, v_chunk, v_vis, v_stage, v_cols,
        array_to_string(ARRAY(SELECT 's.' || c FROM unnest(v_colsa) AS c), ', '),
        array_to_string(ARRAY(SELECT format('%s = s.%s', c, c) FROM unnest(v_colsa) AS c), ', '), v_kc);
    EXECUTE v_sql INTO v_written, v_missed USING v_set, p_geoid, p_chunks, NULL, v_w;
    IF v_missed > 0 THEN
        RAISE EXCEPTION 'chunks of object % in % were written meanwhile by another transaction', p_geoid, v_face
            USING ERRCODE = 'TG300',
                  DETAIL = format('%s new chunk version(s) of the working revision exist already; nothing was written.', v_missed),
                  HINT = 'read the chunks again and retry the write';
    END IF;
    EXECUTE format('TRUNCATE %s', v_stage);
    IF v_written > 0 AND v_versioned
       AND NOT (v_reg.classname IS NULL AND v_objclass = 'feature'
                AND EXISTS (SELECT FROM tgsis.unversioned_features u WHERE u.geoid = p_geoid)) THEN
        PERFORM tgsis.record_changed_objects(v_reg.schemaname, v_reg.tablename, v_keys);
    END IF;
    RETURN v_written;
END
$$;

COMMENT ON FUNCTION tgsis.swap_object_chunks(text, bigint, bigint[], text[]) IS
    'swap the chunk versions a client encoded and staged (tgsis.object_chunks_stage) into one object of a model table stored in chunks, for the calling role: tgsis.write_object_rows'' checks (INSERT and DELETE on the face), the staged chunks'' encoding verified, the visible versions of the chunks given locked and still those the client read (else TG300, nothing written), then written as tgsis.write_chunk_rows writes; returns the chunks written';
