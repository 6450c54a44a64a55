-- tgsis.client_chunks_check(table, caller): refuse (TG100, by name) a chunked table whose chunks the client's encoder cannot write whole.
-- The client's chunk path (tgsis.object_chunks_stage, then
-- tgsis.swap_object_chunks) takes chunks encoded in Python: only of tables
-- keyed by the object alone (not model 2's (geoid, times, chunk)), and only
-- with the arrays that encoder writes. A model table's columns of role
-- 'value' (a G-map dart's acellid and positive: model 1's encoder writes no
-- such arrays) would be left NULL, a silent loss, and of role 'point' (a
-- G-map's vertex: a 2-D array it does not write): refused, naming the columns
-- and the writer to use. A class's property table ('value's and 'vector's:
-- a vector property's 2-D array, slots x k) is encoded whole by its own
-- client path. Both callers ask it, so that neither can be reached with a
-- table the other refuses. p_caller names the calling function in the message.
CREATE FUNCTION tgsis.client_chunks_check(p_table text, p_caller text)
RETURNS void
LANGUAGE plpgsql
STABLE
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_model boolean := (SELECT r.classname IS NULL FROM tgsis.chunk_registry(p_table) r);
    v_bad   text;
BEGIN
    IF cardinality(tgsis.chunk_key(p_table)) <> 1 THEN
        -- (an object's chunks are keyed by more than the object here: model 2's (geoid, times, chunk))
        RAISE EXCEPTION 'tgsis.% is chunked by (%, chunk): tgsis.% writes the chunks of tables keyed by the object alone',
                        quote_ident(p_table), array_to_string(tgsis.chunk_key(p_table), ', '), p_caller
            USING ERRCODE = 'TG100',
                  HINT = format('write its rows through the face tgsis.%I or tgsis.insert_chunk_rows', p_table);
    END IF;
    SELECT string_agg(c.name, ', ' ORDER BY c.colorder) INTO v_bad FROM tgsis.chunk_columns(p_table) c WHERE c.role IN ('value', 'point');
    IF v_model AND v_bad IS NOT NULL THEN
        RAISE EXCEPTION 'tgsis.% has columns tgsis.% does not write: %', quote_ident(p_table), p_caller, v_bad
            USING ERRCODE = 'TG100',
                  HINT = format('write its rows through the face tgsis.%I or tgsis.insert_chunk_rows', p_table);
    END IF;
END
$$;

COMMENT ON FUNCTION tgsis.client_chunks_check(text, text) IS
    'refuse (TG100, naming the columns) a chunked table the client''s chunk path cannot write whole: keyed by more than the object, a model table''s value columns (a class''s scalar and vector properties are written); asked by tgsis.object_chunks_stage and tgsis.swap_object_chunks (p_caller: the name in the message)';

-- internal to the two SECURITY DEFINER functions of the client's chunk path: not executable by PUBLIC
REVOKE ALL ON FUNCTION tgsis.client_chunks_check(text, text) FROM PUBLIC;
