-- tgsis.changed_slot_keys(table, timecol, idcol, keycol, geoid, base, parentset, versionset, since): the (time, id) keys of an object's changed slots in a chunk table.
-- The psql merges by slice of model 2 (tgsis.merge_instants_by_slice: times,
-- vrtxid / trglid) and model 3 (tgsis.merge_periods_by_slice: timem, nodeid /
-- trglid) take as changed, for a vertex or cell table stored in chunks, only
-- the slots whose values or presence differ between the base, the parent's
-- and the version's states (tgsis.storage_changed_rows, as model 1's region
-- engine and tgsis.mesh_merge_work read them), not every slot of a changed
-- chunk: each key's rows are then read at its instant or period, with their
-- class property rows. One statement for both, run on the table's storage by
-- tgsis.storage_run as the caller; p_since the revisions written since the
-- base (the slot's version made or closed in one of them).
CREATE FUNCTION tgsis.changed_slot_keys(p_table tgsis.versioned_tables, p_timecol text, p_idcol text, p_keycol text,
                                        p_geoid bigint, p_base integer[], p_parentset integer[],
                                        p_versionset integer[], p_since integer[])
RETURNS TABLE (t double precision, id bigint)
LANGUAGE sql
VOLATILE
SET search_path = pg_catalog, pg_temp
AS $$
    SELECT r[1]::float8, r[2]::bigint
      FROM tgsis.storage_run(p_table, false, format(
             'SELECT DISTINCT ARRAY[v.%1$I::text, v.%2$I::text] FROM %3$s v WHERE v.%4$I = $1[1]::bigint
                 AND (v.revision = ANY ($2) OR (v.revclosed AND v.lastrevs && $2))',
             p_timecol, p_idcol,
             tgsis.storage_changed_rows(p_table.schemaname, p_table.tablename, ARRAY[p_geoid],
                                        p_base, p_parentset, p_versionset),
             p_keycol),
           p_1 => ARRAY[p_geoid::text], p_2 => p_since) AS r
$$;

-- internal to the merges by slice, as tgsis.storage_changed_rows is (granted alike)
REVOKE ALL ON FUNCTION tgsis.changed_slot_keys(tgsis.versioned_tables, text, text, text, bigint, integer[], integer[],
                                               integer[], integer[]) FROM PUBLIC;
GRANT EXECUTE ON FUNCTION tgsis.changed_slot_keys(tgsis.versioned_tables, text, text, text, bigint, integer[], integer[],
                                                  integer[], integer[]) TO tgsis_reader;

COMMENT ON FUNCTION tgsis.changed_slot_keys(tgsis.versioned_tables, text, text, text, bigint, integer[], integer[], integer[], integer[]) IS
    'the distinct (time, id) keys of object p_geoid''s slots in a vertex or cell table stored in chunks whose values or presence differ between the base and the parent''s and version''s revision sets (tgsis.storage_changed_rows), made or closed since the base; the changed keys of the psql merges by slice of models 2 and 3';
