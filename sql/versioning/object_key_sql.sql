-- tgsis.object_key_sql(type, expression): the SQL expression that turns an object key of a type into its canonical text.
-- For the code that versioning generates (the views' write triggers, dynamic
-- SQL on storage): for types whose cast to text depends on no setting it is
-- the cast itself (the generated code of integer and text keys stays what
-- it was), for the others a call of tgsis.object_key_text. Types with no
-- canonical text (arrays, ranges, json, money, reg*, ...: tgsis.object_key_kind
-- is NULL) are refused as object keys by enable_versioning
-- (tgsis.check_key_canonical); for a table keyed by one from an older
-- release the expression is the cast, as it was then. p_expr must be a
-- column reference or a parenthesized expression.
CREATE FUNCTION tgsis.object_key_sql(p_type oid, p_expr text)
RETURNS text
LANGUAGE sql
IMMUTABLE
PARALLEL SAFE
AS $$
    SELECT CASE tgsis.object_key_kind(p_type)
        WHEN 'function' THEN 'tgsis.object_key_text(' || p_expr || ')'
        ELSE p_expr || '::text'
        END
$$;

COMMENT ON FUNCTION tgsis.object_key_sql(oid, text) IS
    'SQL expression giving the canonical text (independent of the session''s settings) of an object key of type p_type computed by p_expr (the cast to text for types without one, which enable_versioning refuses)';
