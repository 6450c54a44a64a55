-- tgsis.create_hash_partitions(table, partitions, owner): the partitions of a model storage table partitioned by HASH (geoid).
-- The partition scheme of tgsis.partition_model_storage, for row tables and
-- for chunk tables (tgsis.partition_chunk_storage) alike: p_partitions
-- partitions tgsis.<table>_p<r> (r = 0 .. p_partitions - 1, modulus
-- p_partitions), each owned by the storage's owner and commented, so that an
-- object's rows and chunks of every table share a remainder. The parent
-- tgsis.<table> exists already, partitioned by HASH (geoid); its rights and
-- row-level security apply to what is read and written through it (the
-- partitions get no grants of their own: reached directly, they refuse the
-- roles). Internal: tgsis's owner, in the caller's transaction.
CREATE FUNCTION tgsis.create_hash_partitions(p_table text, p_partitions integer, p_owner name)
RETURNS void
LANGUAGE plpgsql
VOLATILE
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_r integer;
BEGIN
    FOR v_r IN 0 .. p_partitions - 1 LOOP
        EXECUTE format('CREATE TABLE tgsis.%I PARTITION OF tgsis.%I FOR VALUES WITH (MODULUS %s, REMAINDER %s)',
                       p_table || '_p' || v_r, p_table, p_partitions, v_r);
        EXECUTE format('ALTER TABLE tgsis.%I OWNER TO %I', p_table || '_p' || v_r, p_owner);
        EXECUTE format('COMMENT ON TABLE tgsis.%I IS %L', p_table || '_p' || v_r,
                       format('partition %s of %s of tgsis.%s (hash of geoid; partition_model_storage)',
                              v_r + 1, p_partitions, p_table));
    END LOOP;
END
$$;

REVOKE ALL ON FUNCTION tgsis.create_hash_partitions(text, integer, name) FROM PUBLIC;

COMMENT ON FUNCTION tgsis.create_hash_partitions(text, integer, name) IS
    'create the p_partitions hash partitions tgsis.<table>_p<r> of tgsis.<table> (partitioned by HASH (geoid)), owned by p_owner and commented; the partition scheme of partition_model_storage for row and chunk tables';
