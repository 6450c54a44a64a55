-- tgsis.create_chunk_insert_trigger(table, chunk table): the statement trigger that checks direct chunk inserts.
-- What roles other than the owners insert into a chunk table (the client's
-- COPY upload, a psql INSERT) is checked by tgsis.chunk_insert_check: the
-- encoding the conversion proves, and open versions of revision 0 while the
-- table is not versioned. The owners (of the chunk table and of schema tgsis)
-- are spared by role name, as tgsis.guard_chunk_storage's triggers are, so a
-- restored dump keeps them spared. One place for the two callers that make a
-- chunk table: tgsis.create_chunk_table and tgsis.partition_chunk_storage
-- (a partitioned table takes the trigger on its root: a statement trigger with
-- a transition table there sees the rows of every partition).
CREATE FUNCTION tgsis.create_chunk_insert_trigger(p_table text, p_chunk regclass)
RETURNS void
LANGUAGE plpgsql
VOLATILE
SET search_path = pg_catalog, pg_temp
AS $$
BEGIN
    EXECUTE format('CREATE TRIGGER tgsis_chunk_insert AFTER INSERT ON %s REFERENCING NEW TABLE AS tgsis_new_chunks '
                   'FOR EACH STATEMENT WHEN (NOT pg_catalog.pg_has_role(current_user, %L::name, ''USAGE'') '
                   'AND NOT pg_catalog.pg_has_role(current_user, %L::name, ''USAGE'')) '
                   'EXECUTE FUNCTION tgsis.chunk_insert_check(%L)',
                   p_chunk, (SELECT pg_get_userbyid(c.relowner) FROM pg_class c WHERE c.oid = p_chunk),
                   (SELECT pg_get_userbyid(n.nspowner) FROM pg_namespace n WHERE n.nspname = 'tgsis'), p_table);
    EXECUTE format('COMMENT ON TRIGGER tgsis_chunk_insert ON %s IS %L', p_chunk,
                   'chunk versions inserted directly by roles other than the owners are encoded as read, and open of revision 0 '
                   'while unversioned (tgsis.chunk_insert_check)');
END
$$;

REVOKE ALL ON FUNCTION tgsis.create_chunk_insert_trigger(text, regclass) FROM PUBLIC;

COMMENT ON FUNCTION tgsis.create_chunk_insert_trigger(text, regclass) IS
    'create the statement trigger tgsis_chunk_insert on a chunk table (tgsis.chunk_insert_check for roles other than the owners); called by tgsis.create_chunk_table and tgsis.partition_chunk_storage';
