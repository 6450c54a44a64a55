-- tgsis.object_chunks_stage(table): the transaction's temporary table into which a client COPYs the chunks it encoded for tgsis.swap_object_chunks.
-- A check-in of a scattered edit touches nearly every chunk of the object;
-- re-aggregating each in SQL (tgsis.write_chunk_rows) costs 3-5 ms a chunk,
-- so the client encodes the touched chunks itself (tgsis._chunks, as the
-- upload does) and sends them in one binary COPY. They go into a temporary
-- table made here, owned by tgsis's owner (tgsis.swap_object_chunks, a
-- SECURITY DEFINER function, reads it: a table the calling role made could
-- not be read by it), with the chunk table's columns that a client's COPY
-- fills (geoid, chunk, revision, holes, [vbase, vtop], the arrays, [_wide]);
-- each array compressed as the chunk table compresses it (the swap then
-- copies the values as they are: compressed once, by the client's COPY);
-- INSERT on it is granted to the calling role. Made once per transaction
-- and table (ON COMMIT DROP: a grant to the role on a table that outlived the
-- transaction would keep DROP ROLE from dropping the role while its session
-- lives, and race the drop of the session's temporary tables after it),
-- emptied at each call; so the stage, the COPY and the swap are one
-- transaction. A class's property table stored in chunks
-- (tgsis.store_class_in_chunks, named as tgsis.chunk_registry names it:
-- 'public.rock_cellpros') is staged the same way (the key column _geoid, the
-- property arrays), in a table named by its chunk table's oid; a stage whose
-- columns are no longer the chunk table's (a property added, renamed or
-- dropped in the transaction) is made anew. Refused by name: a table not
-- stored in chunks (TG100); a temporary table of that name the session made
-- itself (42501).
-- Returns the table's name, schema-qualified (pg_temp).
CREATE FUNCTION tgsis.object_chunks_stage(p_table text)
RETURNS text
LANGUAGE plpgsql
VOLATILE
SECURITY DEFINER
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_reg   record;
    v_stage text;
    v_cols  text;
    v_col   record;
BEGIN
    SELECT * INTO v_reg FROM tgsis.chunk_registry(p_table) r WHERE r.chunkcolumn IS NOT NULL;
    IF NOT FOUND OR NOT tgsis.stored_in_chunks(v_reg.schemaname, v_reg.tablename) THEN
        RAISE EXCEPTION '% is not stored in chunks',
                        CASE WHEN strpos(coalesce(p_table, ''), '.') > 0 THEN p_table ELSE 'tgsis.' || coalesce(quote_ident(p_table), 'NULL') END
            USING ERRCODE = 'TG100',
                  DETAIL = 'tgsis.object_chunks_stage stages chunks of the model tables switched to chunks (tgsis.stored_in_chunks) '
                           'and of the property tables of classes switched by tgsis.store_class_in_chunks.',
                  HINT = 'write the rows of a table stored as rows through its view or storage';
    END IF;
    PERFORM tgsis.client_chunks_check(p_table, 'object_chunks_stage');  -- TG100: keys, a model table's value columns
    v_stage := format('pg_temp.%I', 'tgsis_object_chunks_'
                                    || CASE WHEN v_reg.classname IS NULL THEN p_table ELSE tgsis.chunk_table_of(p_table)::oid::text END);
    v_cols := array_to_string(ARRAY[quote_ident(v_reg.keycolumn), 'chunk', 'revision', 'holes']
                              || CASE WHEN EXISTS (SELECT FROM tgsis.chunk_columns(p_table) c WHERE c.role = 'ref')
                                      THEN ARRAY['vbase', 'vtop'] ELSE '{}'::text[] END
                              || ARRAY(SELECT quote_ident(c.name) FROM tgsis.chunk_columns(p_table) c
                                        WHERE c.role IN ('float', 'ref', 'value', 'vector') ORDER BY c.colorder)
                              || ARRAY(SELECT quote_ident(c.name || '_wide') FROM tgsis.chunk_columns(p_table) c
                                        WHERE c.role = 'ref' ORDER BY c.colorder), ', ');
    IF to_regclass(v_stage) IS NOT NULL
       AND (SELECT c.relowner FROM pg_class c WHERE c.oid = to_regclass(v_stage))
           <> (SELECT r.oid FROM pg_roles r WHERE r.rolname = current_user) THEN
        RAISE EXCEPTION 'the session''s table % was not made by tgsis.object_chunks_stage', v_stage
            USING ERRCODE = 'insufficient_privilege', HINT = 'drop the temporary table and write again';
    END IF;
    IF to_regclass(v_stage) IS NOT NULL
       AND (SELECT string_agg(quote_ident(a.attname), ', ' ORDER BY a.attnum) FROM pg_attribute a
             WHERE a.attrelid = to_regclass(v_stage) AND a.attnum > 0 AND NOT a.attisdropped) IS DISTINCT FROM v_cols THEN
        EXECUTE format('DROP TABLE %s', v_stage);  -- (of the columns before a property was added, renamed or dropped)
    END IF;
    IF to_regclass(v_stage) IS NULL THEN
        EXECUTE format('CREATE TEMP TABLE %s ON COMMIT DROP AS SELECT %s FROM %s WITH NO DATA', v_stage, v_cols, tgsis.chunk_table_of(p_table));
        -- each array compressed as the chunk table compresses it: the swap then copies the compressed values as they are
        FOR v_col IN SELECT a.attname, a.attcompression FROM pg_attribute a
                      WHERE a.attrelid = tgsis.chunk_table_of(p_table) AND a.attnum > 0 AND NOT a.attisdropped
                        AND a.attcompression <> '' AND quote_ident(a.attname) = ANY (string_to_array(v_cols, ', ')) LOOP
            EXECUTE format('ALTER TABLE %s ALTER COLUMN %I SET COMPRESSION %s', v_stage, v_col.attname,
                           CASE v_col.attcompression WHEN 'l' THEN 'lz4' ELSE 'pglz' END);
        END LOOP;
    ELSE
        EXECUTE format('TRUNCATE %s', v_stage);
    END IF;
    IF tgsis.calling_role() <> current_user AND NOT has_table_privilege(tgsis.calling_role(), v_stage, 'INSERT') THEN
        EXECUTE format('GRANT INSERT ON %s TO %I', v_stage, tgsis.calling_role());
    END IF;
    RETURN v_stage;
END
$$;

COMMENT ON FUNCTION tgsis.object_chunks_stage(text) IS
    'the transaction''s temporary table (owned by tgsis''s owner, INSERT granted to the calling role, emptied, dropped at commit) into which a client COPYs the chunk versions it encoded for tgsis.swap_object_chunks, of a model table or of a class''s property table stored in chunks; returns its name';
