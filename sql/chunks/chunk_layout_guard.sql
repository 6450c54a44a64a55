-- tgsis.chunk_layout_guard(): the chunk layout of a registered table cannot change under its chunks.
-- A chunk table's rows mean what the registry said when they were written:
-- the decoded face (tgsis.<t>_chunk_rows) is built with the chunk size of its
-- day, the writer (tgsis.write_chunk_rows) and the codec read the registry
-- each call. Changing tgsis.model_tables.chunkcolumn, chunkrefs or chunksize
-- while tgsis.<t>_chunk exists would make them disagree (a vertex written
-- twice at two places, read at the wrong id: the hostile review found it), so
-- the change is refused (TG202) until the chunks are moved back to rows and
-- the chunk table dropped. Only tgsis's owner writes the registry; this keeps
-- the owner's own hand from corrupting the storage. Renaming or deleting a
-- registered row is refused too while its chunk table exists.
CREATE FUNCTION tgsis.chunk_layout_guard()
RETURNS trigger
LANGUAGE plpgsql
VOLATILE
SET search_path = pg_catalog, pg_temp
AS $$
BEGIN
    IF OLD.chunkcolumn IS NULL OR to_regclass(format('tgsis.%I', OLD.tablename || '_chunk')) IS NULL THEN
        RETURN CASE WHEN TG_OP = 'DELETE' THEN OLD ELSE NEW END;
    END IF;
    IF TG_OP = 'DELETE' OR (OLD.tablename, OLD.chunkcolumn, OLD.chunkrefs, OLD.chunksize)
                           IS DISTINCT FROM (NEW.tablename, NEW.chunkcolumn, NEW.chunkrefs, NEW.chunksize) THEN
        RAISE EXCEPTION 'the chunk layout of tgsis.% cannot change while tgsis.% holds its chunks',
                        quote_ident(OLD.tablename), quote_ident(OLD.tablename || '_chunk')
            USING ERRCODE = 'TG202',
                  DETAIL = format('Its rows are stored as chunks of %s ids by %s; the decoded face and the writer would read them differently.',
                                  OLD.chunksize, OLD.chunkcolumn),
                  HINT = 'move the chunks back to rows (tgsis.chunks_to_rows) and drop the chunk table first';
    END IF;
    RETURN NEW;
END
$$;

REVOKE ALL ON FUNCTION tgsis.chunk_layout_guard() FROM PUBLIC;

CREATE TRIGGER tgsis_chunk_layout_guard BEFORE UPDATE OR DELETE ON tgsis.model_tables
    FOR EACH ROW EXECUTE FUNCTION tgsis.chunk_layout_guard();

COMMENT ON FUNCTION tgsis.chunk_layout_guard() IS
    'trigger on tgsis.model_tables: refuses (TG202) a change of a table''s chunk layout (chunkcolumn, chunkrefs, chunksize), its renaming or deletion while tgsis.<table>_chunk exists';
COMMENT ON TRIGGER tgsis_chunk_layout_guard ON tgsis.model_tables IS
    'keeps the chunk layout of a table fixed while its chunk table exists (tgsis.chunk_layout_guard)';
