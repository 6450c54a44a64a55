-- tgsis.create_chunk_table(table): create <schema>.<table>_chunk, the chunk storage of a model table or of a class's property table (issue 40).
-- The layout is the contract of docs/storage.md ("Chunks and the mapping of
-- ids", "Compression, bit-exact", "Versioning of chunks"): the row table's key
-- with its local-id column replaced by chunk (= id >> log2(chunksize)) and put
-- last, then
-- revision, lastrevs, revclosed as in <table>_ver, holes, vbase and vtop (a
-- bound of its vertex ids: the readers of the cells on given vertices skip the
-- chunks whose [vbase, vtop] misses them) for a table
-- with vertex-id columns, one array per other column in the row table's order,
-- and a <ref>_wide bigint[] per vertex-id column. The columns come from the
-- registry and the live storage (tgsis.chunk_columns), never from a list typed
-- here. Compression is chosen now from the server: lz4 on the double
-- precision[] columns when it was built with lz4, else pglz; pglz on the
-- integer, bigint and smallint arrays. Indexes: the primary key and the two
-- revision indexes every versioned storage has (a BRIN on revision, a btree on
-- the object key of closed versions: tgsis.create_revision_indexes, which
-- names <table>_ver and so is not reused), and for a point column whose row
-- table has a GiST index over it (md_vertex's md_vertex_point_idx) a GiST
-- index on each chunk version's box, <table>_chunk_<column>_box_idx
-- (tgsis.point_chunk_box, an expression: every writer keeps it right; read by
-- tgsis.md_vertices_in_box). Grants and row-level security are
-- the row table's storage's (tgsis.grant_model_tables, tgsis.protect_model_tables),
-- copied from the catalog: the same roles reach the same objects' chunks.
-- A statement trigger checks what roles other than the owners insert
-- directly (tgsis.chunk_insert_check: the encoding, unversioned revisions).
-- Nothing reads or writes chunk tables yet besides tgsis.write_chunk_rows and
-- the decoded face (tgsis.create_chunk_view); the storage switch comes next.
-- Not idempotent: a second call refuses by name (TG201). Runs with the
-- caller's rights (tgsis's owner, who owns the storage). A class's property
-- table (tgsis.chunk_registry, 'schema.table') gets its chunk table in its
-- own schema, with one array per property of the property's own type, a
-- vector property's two-dimensional (slots x k); a model table's point
-- (a G-map's vertex, role 'point') is a two-dimensional double precision[]
-- (slots x m), lz4 as the coordinates
-- (docs/storage.md, "Property chunks: the contract").
CREATE FUNCTION tgsis.create_chunk_table(p_table text)
RETURNS regclass
LANGUAGE plpgsql
VOLATILE
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_reg     record;
    v_name    text;
    v_storage regclass;
    v_chunk   regclass;
    v_float   text;
    v_coldesc text;
    v_refs    text[];
    v_defs    text[] := '{}';
    v_c       record;
    v_key     text;
BEGIN
    PERFORM FROM tgsis.chunk_columns(p_table);  -- TG200 when not registered for chunks, TG100 when it does not fit
    SELECT * INTO v_reg FROM tgsis.chunk_registry(p_table) r;
    v_name := v_reg.tablename || '_chunk';
    IF octet_length(v_name || '_rows') > 63 THEN
        RAISE EXCEPTION 'table name % is too long for a chunk table', quote_literal(p_table)
            USING ERRCODE = 'TG101', DETAIL = 'The chunk table <table>_chunk and its face <table>_chunk_rows must fit in 63 bytes.';
    END IF;
    IF to_regclass(format('%I.%I', v_reg.schemaname, v_name)) IS NOT NULL THEN
        RAISE EXCEPTION '% exists already', format('%I.%I', v_reg.schemaname, v_name)
            USING ERRCODE = 'TG201', DETAIL = format('The chunk table of %I.%I was created before.', v_reg.schemaname, v_reg.tablename);
    END IF;
    v_storage := tgsis.storage_table(v_reg.schemaname, v_reg.tablename)::regclass;
    -- lz4 when the server was built with it (a build option: default_toast_compression then lists it)
    v_float := CASE WHEN EXISTS (SELECT FROM pg_settings WHERE name = 'default_toast_compression' AND 'lz4' = ANY (enumvals))
                    THEN 'lz4' ELSE 'pglz' END;

    -- the key (in the primary key's order, the chunk column replaced and moved last: the readers and the face's
    -- writer match a row's chunk by the key before revision, chunk last; a G-map involution's key (geoid, dartid,
    -- level) is (geoid, level, chunk)), the versioning columns, holes, vbase
    FOR v_c IN SELECT c.name, c.role FROM tgsis.chunk_columns(p_table) c WHERE c.keyorder IS NOT NULL
                ORDER BY c.role = 'chunk', c.keyorder LOOP
        v_key := concat_ws(', ', v_key, CASE WHEN v_c.role = 'chunk' THEN 'chunk' ELSE quote_ident(v_c.name) END);
        v_defs := v_defs || CASE WHEN v_c.role = 'chunk' THEN 'chunk bigint NOT NULL'
                                 ELSE format('%I %s NOT NULL', v_c.name,
                                             (SELECT format_type(a.atttypid, a.atttypmod) FROM pg_attribute a
                                               WHERE a.attrelid = v_storage AND a.attname = v_c.name)) END;
    END LOOP;
    v_defs := v_defs || ARRAY['revision integer NOT NULL',
                              'lastrevs integer[] COMPRESSION pglz NOT NULL DEFAULT ''{}''',
                              'revclosed boolean GENERATED ALWAYS AS (cardinality(lastrevs) > 0) STORED',
                              'holes smallint[] COMPRESSION pglz'];
    v_refs := ARRAY(SELECT c.name FROM tgsis.chunk_columns(p_table) c WHERE c.role = 'ref' ORDER BY c.colorder);
    IF cardinality(v_refs) > 0 THEN
        v_defs := v_defs || ARRAY['vbase bigint', 'vtop bigint'];
    END IF;
    FOR v_c IN SELECT c.name, c.role, c.typename FROM tgsis.chunk_columns(p_table) c WHERE c.keyorder IS NULL ORDER BY c.colorder LOOP
        v_defs := v_defs || CASE WHEN v_c.role IN ('float', 'point') THEN format('%I double precision[] COMPRESSION %s', v_c.name, v_float)
                                 -- a property: an array of its own type (lz4 for doubles, as coordinates)
                                 -- (a vector property: the same array type, two-dimensional, slots x k)
                                 WHEN v_c.role IN ('value', 'vector') THEN format('%I %s[] COMPRESSION %s', v_c.name, v_c.typename,
                                                                     CASE WHEN v_c.typename = 'double precision' THEN v_float
                                                                          ELSE 'pglz' END)
                                 ELSE format('%I integer[] COMPRESSION pglz', v_c.name) END;
    END LOOP;
    v_defs := v_defs || ARRAY(SELECT format('%I bigint[] COMPRESSION pglz', r || '_wide') FROM unnest(v_refs) WITH ORDINALITY AS u(r, o)
                               ORDER BY o);
    EXECUTE format('CREATE TABLE %I.%I (%s, PRIMARY KEY (%s, revision))', v_reg.schemaname, v_name, array_to_string(v_defs, ', '), v_key);
    v_chunk := format('%I.%I', v_reg.schemaname, v_name)::regclass;
    -- the revision indexes of every versioned storage (tgsis.create_revision_indexes says why)
    EXECUTE format('CREATE INDEX %I ON %s USING brin (revision) WITH (autosummarize = on)', v_name || '_revision_idx', v_chunk);
    EXECUTE format('CREATE INDEX %I ON %s (%I) WHERE revclosed', v_name || '_closed_idx', v_chunk, v_reg.keycolumn);
    -- a point column whose row table answers box queries by a GiST index (md_vertex_point_idx on cube(coordinate)):
    -- the box of each chunk version, GiST-indexed (tgsis.point_chunk_box, an expression: every writer keeps it right),
    -- and its m by object, for the chunks whose points have fewer coordinates than a box query's axes
    -- (tgsis.md_vertices_in_box: the cube type's && would need the box's other axes to hold 0)
    FOR v_c IN SELECT c.name FROM tgsis.chunk_columns(p_table) c WHERE c.role = 'point'
                  AND EXISTS (SELECT FROM pg_index i JOIN pg_class ic ON ic.oid = i.indexrelid JOIN pg_am am ON am.oid = ic.relam
                               WHERE i.indrelid = v_storage AND am.amname = 'gist'
                                 AND pg_get_expr(i.indexprs, i.indrelid) LIKE format('%%(%s)%%', quote_ident(c.name)))
                ORDER BY c.colorder LOOP
        EXECUTE format('CREATE INDEX %I ON %s USING gist (tgsis.point_chunk_box(%I))', v_name || '_' || v_c.name || '_box_idx',
                       v_chunk, v_c.name);
    END LOOP;

    -- comments, generated from the row table's
    EXECUTE format('COMMENT ON TABLE %s IS %L', v_chunk,
                   format('chunk storage of %s.%s (issue 40, docs/storage.md): one row per block of %s consecutive %s of one object '
                          'and per chunk version; nothing reads it yet but tgsis.write_chunk_rows and %s.%s_rows',
                          v_reg.schemaname, v_reg.tablename, v_reg.chunksize, v_reg.chunkcolumn, v_reg.schemaname, v_name));
    FOR v_c IN SELECT c.name, c.role, c.size FROM tgsis.chunk_columns(p_table) c ORDER BY c.colorder LOOP
        v_coldesc := col_description(v_storage, (SELECT a.attnum FROM pg_attribute a WHERE a.attrelid = v_storage AND a.attname = v_c.name)::integer);
        IF v_c.role = 'chunk' THEN
            EXECUTE format('COMMENT ON COLUMN %s.chunk IS %L', v_chunk,
                           format('chunk number: the ids %s = chunk * %s + slot - 1 (slots 1..%s; %s: %s)', v_c.name, v_reg.chunksize,
                                  v_reg.chunksize, v_c.name, coalesce(v_coldesc, 'local id')));
        ELSIF v_c.role = 'key' THEN
            EXECUTE format('COMMENT ON COLUMN %s.%I IS %L', v_chunk, v_c.name,
                           coalesce(v_coldesc, format('key column %s of %s.%s', v_c.name, v_reg.schemaname, v_reg.tablename)));
        ELSIF v_c.role = 'value' THEN
            EXECUTE format('COMMENT ON COLUMN %s.%I IS %L', v_chunk, v_c.name,
                           format('%s per slot (NULL: no value, or a hole when holes lists the slot)', coalesce(v_coldesc, v_c.name)));
        ELSIF v_c.role = 'vector' THEN
            EXECUTE format('COMMENT ON COLUMN %s.%I IS %L', v_chunk, v_c.name,
                           format('%s: slots x %s, a vector per slot (a row of %s NULLs: no value, or a hole when holes lists '
                                  'the slot)', coalesce(v_coldesc, v_c.name), v_c.size, v_c.size));
        ELSIF v_c.role = 'point' THEN
            EXECUTE format('COMMENT ON COLUMN %s.%I IS %L', v_chunk, v_c.name,
                           format('%s: slots x m, a point per slot, bit-exact, m the object''s (a row of m NULLs: a hole)',
                                  coalesce(v_coldesc, v_c.name)));
        ELSIF v_c.role = 'float' THEN
            EXECUTE format('COMMENT ON COLUMN %s.%I IS %L', v_chunk, v_c.name,
                           format('%s per slot, bit-exact (NULL: a hole)', coalesce(v_coldesc, v_c.name)));
        ELSE
            EXECUTE format('COMMENT ON COLUMN %s.%I IS %L', v_chunk, v_c.name,
                           format('%s per slot, as %s - %s (NULL: a hole, or every value is in %s_wide)', coalesce(v_coldesc, v_c.name),
                                  v_c.name, CASE WHEN v_c.name = v_refs[1] THEN 'vbase' ELSE v_refs[1] END, v_c.name));
            EXECUTE format('COMMENT ON COLUMN %s.%I IS %L', v_chunk, v_c.name || '_wide',
                           format('%s per slot as absolute ids, only when some difference of the chunk does not fit integer (then vbase is NULL)',
                                  v_c.name));
        END IF;
    END LOOP;
    EXECUTE format('COMMENT ON COLUMN %s.revision IS %L', v_chunk, 'revision in which this chunk version was written (0: unversioned storage)');
    EXECUTE format('COMMENT ON COLUMN %s.lastrevs IS %L', v_chunk,
                   'revisions in which this chunk version stopped being current (rewritten or emptied there); empty while live');
    EXECUTE format('COMMENT ON COLUMN %s.revclosed IS %L', v_chunk,
                   'lastrevs is not empty (kept by PostgreSQL): lets reads skip the array for live chunk versions');
    EXECUTE format('COMMENT ON COLUMN %s.holes IS %L', v_chunk,
                   'slots (1-based, ascending) of absent ids below the last present slot; NULL when none');
    IF cardinality(v_refs) > 0 THEN
        EXECUTE format('COMMENT ON COLUMN %s.vbase IS %L', v_chunk,
                       'the smallest vertex id among all ref values of the chunk; NULL when the _wide columns hold them');
        EXECUTE format('COMMENT ON COLUMN %s.vtop IS %L', v_chunk,
                       'a bound of the vertex ids of the chunk: vbase + 2 * the largest relative value (0 at least), or the largest '
                       '_wide id; the largest bigint when that overflows; readers of the cells on given vertices skip chunks whose '
                       '[vbase, vtop] misses them');
    END IF;

    -- the rights of the row table's storage (its grants; its row-level security, policies and their comments)
    PERFORM tgsis.copy_relation_rights(v_storage, v_chunk);
    -- a class's property table is written through its face only (tgsis.chunk_face_write, as the owner): the roles the
    -- class table lets write keep reading the chunks, and write none directly (an UPDATE of a chunk is checked by nothing)
    IF v_reg.classname IS NOT NULL THEN
        FOR v_c IN SELECT DISTINCT a.grantee FROM pg_class c, aclexplode(c.relacl) AS a
                    WHERE c.oid = v_chunk AND a.grantee <> c.relowner AND a.privilege_type <> 'SELECT' LOOP
            EXECUTE format('REVOKE INSERT, UPDATE, DELETE, TRUNCATE, REFERENCES, TRIGGER ON %s FROM %s', v_chunk,
                           CASE WHEN v_c.grantee = 0 THEN 'PUBLIC' ELSE quote_ident(pg_get_userbyid(v_c.grantee)) END);
        END LOOP;
    END IF;
    -- what the roles that keep INSERT (the client's COPY upload) write is checked (tgsis.chunk_insert_check)
    PERFORM tgsis.create_chunk_insert_trigger(p_table, v_chunk);
    RETURN v_chunk;
END
$$;

REVOKE ALL ON FUNCTION tgsis.create_chunk_table(text) FROM PUBLIC;

COMMENT ON FUNCTION tgsis.create_chunk_table(text) IS
    'create tgsis.<table>_chunk, the chunk storage of a model table registered for chunks (tgsis.model_tables.chunkcolumn), per the contract of docs/storage.md: columns from the live storage, lz4 or pglz compression, primary key and revision indexes (and a point column''s box index when its row table has a GiST index over it), comments, the storage''s grants and row-level security, the check of direct inserts (tgsis.chunk_insert_check); TG200 for a table not registered for chunks, TG201 when it exists';
