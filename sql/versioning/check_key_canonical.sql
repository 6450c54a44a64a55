-- tgsis.check_key_canonical(table, column): refuse (TG100) an object key column whose keys have no canonical text.
-- tgsis names objects by their keys as text (locks, notes of changed objects,
-- conflicts, advisory lock keys), which must be one text per key whatever
-- the session's settings (tgsis.object_key_sql): enable_versioning refuses
-- a key of a type without one (tgsis.object_key_kind: arrays, ranges, json,
-- money, ...) and a column of a nondeterministic collation (its equality
-- holds keys of different texts to be one key), naming the type or the
-- collation.
CREATE FUNCTION tgsis.check_key_canonical(p_table regclass, p_column text)
RETURNS void
LANGUAGE plpgsql
STABLE
AS $$
DECLARE
    v_type oid;
    v_coll oid;
BEGIN
    SELECT a.atttypid, a.attcollation INTO v_type, v_coll
      FROM pg_catalog.pg_attribute a
     WHERE a.attrelid = p_table AND a.attname = p_column AND NOT a.attisdropped;
    IF tgsis.object_key_kind(v_type) IS NULL THEN
        RAISE EXCEPTION 'the object key column % of % is of type %, which has no text independent of the session''s settings',
                quote_ident(p_column), p_table, pg_catalog.format_type(v_type, NULL)
            USING ERRCODE = 'TG100',
                  DETAIL = 'tgsis names objects by their keys as text (locks, notes of changes, conflicts), which must be one text per key in every session.',
                  HINT = 'key the objects by a column of a scalar type: an integer, text, uuid, date, timestamp(tz), time, float, numeric, interval, bytea, ...';
    END IF;
    IF v_coll <> 0 AND NOT (SELECT c.collisdeterministic FROM pg_catalog.pg_collation c WHERE c.oid = v_coll) THEN
        RAISE EXCEPTION 'the object key column % of % has the nondeterministic collation %', quote_ident(p_column), p_table,
                (SELECT quote_ident(c.collname) FROM pg_catalog.pg_collation c WHERE c.oid = v_coll)
            USING ERRCODE = 'TG100',
                  DETAIL = 'Its equality holds keys of different texts to be one key; tgsis names objects by their keys as text.',
                  HINT = 'give the column a deterministic collation (ALTER TABLE ... ALTER COLUMN ... TYPE text COLLATE "C")';
    END IF;
END
$$;

COMMENT ON FUNCTION tgsis.check_key_canonical(regclass, text) IS
    'raise TG100 unless the object key column of a table to version has a canonical text (tgsis.object_key_kind) and a deterministic collation';
