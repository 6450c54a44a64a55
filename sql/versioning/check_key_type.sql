-- tgsis.check_key_type(storage, column): refuse (TG100) an object key column whose type is not built into PostgreSQL or has no canonical text.
-- tgsis's definer code casts object keys to and from text as tgsis's owner
-- (validating keys, reading keys of rows written directly). enable_versioning
-- refuses such keys, but a table's owner can change the column's type
-- afterwards; a domain's check or a cast of a type of its own would then be
-- the owner's code run as tgsis's owner. So the definer code checks the type
-- again each time, before it casts.
-- Keys are also compared as text, which must be one text per key whatever
-- the session's settings (tgsis.object_key_sql): types without such a text
-- (arrays, ranges, json, money, ...) and columns of a nondeterministic
-- collation (whose equality holds different texts to be one key) are
-- refused too, naming the type or the collation.
CREATE FUNCTION tgsis.check_key_type(p_storage regclass, p_column text)
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
     WHERE a.attrelid = p_storage AND a.attname = p_column AND NOT a.attisdropped;
    IF v_type IS NULL OR v_type >= 16384 THEN
        RAISE EXCEPTION 'the object key column % of % is %', quote_ident(p_column), p_storage,
                CASE WHEN v_type IS NULL THEN 'missing' ELSE format('of type %s, which is not built into PostgreSQL',
                                                                   pg_catalog.format_type(v_type, NULL)) END
            USING ERRCODE = 'TG100',
                  DETAIL = 'tgsis reads and compares object keys as its owner; a type of one''s own could run its owner''s code there.',
                  HINT = 'key the objects by a column of a built-in type (integer, bigint, text, uuid, ...)';
    END IF;
    IF tgsis.object_key_sql(v_type, 'k') IS NULL THEN
        RAISE EXCEPTION 'the object key column % of % is of type %, which has no text independent of the session''s settings',
                quote_ident(p_column), p_storage, pg_catalog.format_type(v_type, NULL)
            USING ERRCODE = 'TG100',
                  DETAIL = 'tgsis names objects by their keys as text (locks, notes of changes, conflicts), which must be one text per key in every session.',
                  HINT = 'key the objects by a column of a scalar type: an integer, text, uuid, date, timestamp(tz), time, float, numeric, interval, bytea, ...';
    END IF;
    IF v_coll <> 0 AND NOT (SELECT c.collisdeterministic FROM pg_catalog.pg_collation c WHERE c.oid = v_coll) THEN
        RAISE EXCEPTION 'the object key column % of % has the nondeterministic collation %', quote_ident(p_column), p_storage,
                (SELECT quote_ident(c.collname) FROM pg_catalog.pg_collation c WHERE c.oid = v_coll)
            USING ERRCODE = 'TG100',
                  DETAIL = 'Its equality holds keys of different texts to be one key; tgsis names objects by their keys as text.',
                  HINT = 'give the column a deterministic collation (ALTER TABLE ... ALTER COLUMN ... TYPE text COLLATE "C")';
    END IF;
END
$$;

COMMENT ON FUNCTION tgsis.check_key_type(regclass, text) IS
    'raise TG100 unless the object key column of a versioned table''s storage is of a built-in type with a canonical text (tgsis.object_key_sql) and a deterministic collation (checked before definer code casts keys)';
