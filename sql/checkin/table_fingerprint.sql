-- tgsis.table_fingerprint(schema, table, keyfield, idfield, keys): row count and xor of row hashes of some objects' rows.
-- Each row hashes as the xor of its columns' 64-bit extended hashes, each
-- seeded by the row's id and the column's position: equal rows hash equal,
-- swapping values between rows or columns changes the hash, and no row text
-- is built (twice as fast as hash_record_extended, which also needs a hash
-- function for every column type). A NULL hashes as a constant of its column.
-- The key and id columns are not hashed themselves: the key is the same on
-- every row counted (a row leaving the object changes the count) and a
-- changed id changes the seeds of the row's other columns.
-- Read through the table's name: through the versioned view when versioning is on.
-- A model table or a class's property table stored in chunks
-- (tgsis.stored_in_chunks(schema, table)) is hashed per chunk, not per row (docs/storage.md, "What each bulk path does on chunks"):
-- each chunk version the session sees hashes as the first 64 bits of the md5
-- of its chunk number and the send form of every other column (a time key
-- such as model 2's times, holes, vbase,
-- the arrays: the doubles bit for bit, so -0.0 differs from 0.0 there where
-- the row hash takes them as equal), and the count is of chunks. The
-- encoding of a content is unique (the contract: arrays end on a present
-- slot, vbase relative refs unless they do not fit), so equal content hashes
-- equal; a fingerprint taken on rows never equals one taken on chunks (a
-- check-out from before the storage switch is refused once at check-in,
-- TG304).
-- The seed is (id << 6) # position: id * 64 + position wherever that fits a
-- bigint and the position is below 64 (the same fingerprint as 0.2.0's
-- id * 64 + position), and no error for an id of 2**57 or more, which the
-- product failed on ("bigint out of range": such an object could not be checked
-- out). For a column at position 64 or more the seed differs from 0.2.0's: a
-- check-out of such a wide class from before the upgrade is refused once at
-- check-in (TG304).
-- Values hashed as text (timestamps, dates, the geometry row) are written
-- with fixed settings: a check-out in one session and a check-in in another
-- (another TimeZone, DateStyle or extra_float_digits) compare the same text.
CREATE FUNCTION tgsis.table_fingerprint(p_schema text, p_table text, p_keyfield text, p_idfield text, p_keys bigint[])
RETURNS text
LANGUAGE plpgsql
STABLE
SET DateStyle = 'ISO, YMD'
SET TimeZone = 'UTC'
SET IntervalStyle = 'postgres'
SET extra_float_digits = 1
SET bytea_output = 'hex'
AS $$
DECLARE
    v_hash   text;
    v_result text;
BEGIN
    IF to_regclass(format('%I.%I', p_schema, p_table)) IS NULL THEN
        RAISE EXCEPTION 'table %.% does not exist', quote_ident(p_schema), quote_ident(p_table) USING ERRCODE = 'TG200';
    END IF;
    IF tgsis.stored_in_chunks(p_schema, p_table) THEN
        -- the chunk table's own columns, after its key (NULL: a byte an array's send form never starts with)
        SELECT string_agg(format('coalesce(%s(r.%I), ''\x01''::bytea)',
                                 CASE WHEN a.attndims > 0 OR t.typcategory = 'A' THEN 'array_send'
                                      WHEN t.typname = 'float8' THEN 'float8send'  -- a time key (model 2's times), by its bits
                                      ELSE 'int8send' END,
                                 a.attname), ' || ' ORDER BY a.attnum)
          INTO v_hash
          FROM pg_attribute a JOIN pg_type t ON t.oid = a.atttypid
         WHERE a.attrelid = format('%I.%I', p_schema, p_table || '_chunk')::regclass AND a.attnum > 0 AND NOT a.attisdropped
           AND a.attname NOT IN (p_keyfield, 'chunk', 'revision', 'lastrevs', 'revclosed');
        EXECUTE format('SELECT count(*) || '':'' || coalesce(bit_xor((''x'' || left(md5(int8send(r.chunk) || %s), 16))::bit(64)::bigint), 0)
                          FROM %I.%I r
                         WHERE r.%I = ANY ($1)
                           AND ($2 IS NULL OR (%s))',
                       v_hash, p_schema, p_table || '_chunk', p_keyfield, tgsis.visible_versions('r', '$2'))
           INTO v_result
          USING p_keys, CASE WHEN EXISTS (SELECT FROM tgsis.versioned_tables t WHERE t.schemaname = p_schema AND t.tablename = p_table)
                             THEN tgsis.get_revisions() END;
        RETURN v_result;
    END IF;
    SELECT string_agg(format(
               'coalesce(%s, %s)',
               CASE t.typname
                   WHEN 'int8' THEN format('hashint8extended(r.%I, (r.%I << 6) # %s)', a.attname, p_idfield, a.attnum)
                   WHEN 'int4' THEN format('hashint4extended(r.%I, (r.%I << 6) # %s)', a.attname, p_idfield, a.attnum)
                   WHEN 'int2' THEN format('hashint4extended(r.%I, (r.%I << 6) # %s)', a.attname, p_idfield, a.attnum)
                   WHEN 'bool' THEN format('hashint4extended(r.%I::int, (r.%I << 6) # %s)', a.attname, p_idfield, a.attnum)
                   WHEN 'float8' THEN format('hashfloat8extended(r.%I, (r.%I << 6) # %s)', a.attname, p_idfield, a.attnum)
                   WHEN 'float4' THEN format('hashfloat8extended(r.%I, (r.%I << 6) # %s)', a.attname, p_idfield, a.attnum)
                   WHEN 'numeric' THEN format('hash_numeric_extended(r.%I, (r.%I << 6) # %s)', a.attname, p_idfield, a.attnum)
                   ELSE format('hashtextextended(r.%I::text, (r.%I << 6) # %s)', a.attname, p_idfield, a.attnum)
               END,
               a.attnum), ' # ' ORDER BY a.attnum)
      INTO v_hash
      FROM pg_attribute a JOIN pg_type t ON t.oid = a.atttypid
     WHERE a.attrelid = format('%I.%I', p_schema, p_table)::regclass AND a.attnum > 0 AND NOT a.attisdropped
       AND a.attname NOT IN (p_keyfield, p_idfield);
    -- the key is the same on every row counted, and the id seeds every other column's hash
    v_hash := coalesce(v_hash, format('hashint8extended(r.%I, 0)', p_idfield));
    -- a versioned table is read from its storage with the view's predicate and the session's
    -- revision set as a parameter: the view's own calls to tgsis.get_revisions() would keep
    -- the scan from running in parallel (measured: twice as slow)
    IF EXISTS (SELECT FROM tgsis.versioned_tables t WHERE t.schemaname = p_schema AND t.tablename = p_table) THEN
        EXECUTE format('SELECT count(*) || '':'' || coalesce(bit_xor(%s), 0) FROM %I.%I r
                         WHERE r.%I = ANY ($1) AND %s',
                       v_hash, p_schema, p_table || '_ver', p_keyfield, tgsis.visible_versions('r', '$2'))
           INTO v_result USING p_keys, tgsis.get_revisions();
    ELSE
        EXECUTE format('SELECT count(*) || '':'' || coalesce(bit_xor(%s), 0) FROM %I.%I r WHERE r.%I = ANY ($1)',
                       v_hash, p_schema, p_table, p_keyfield)
           INTO v_result USING p_keys;
    END IF;
    RETURN v_result;
END
$$;

COMMENT ON FUNCTION tgsis.table_fingerprint(text, text, text, text, bigint[]) IS
    'row count and xor of per-row hashes (columns hashed with seeds from the row id and column position) of the rows of a table whose keyfield is one of keys, as the session sees them; for a table stored in chunks (a model table, a class''s property table), the count and xor of per-chunk hashes (md5 of the chunk number and the chunk''s send forms) of the chunk versions the session sees';
