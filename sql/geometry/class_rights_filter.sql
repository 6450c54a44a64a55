-- tgsis.class_rights_filter(column, privilege, alias): the condition that keeps from a statement the rows of classes its role lacks a right on.
-- One text for the two places that apply per-class rights to the model tables
-- every class shares: their row-level security policies
-- (tgsis.protect_model_tables) and the WHERE clause of their versioned views
-- (tgsis.create_versioned_view, and the upgrade that adds it to views made
-- before). It passes current_user, the role the statement runs as (inside a
-- SECURITY DEFINER function of another role, that function's owner), beside
-- the calling role that tgsis.class_denied_geoids counts anyway: a class is
-- kept from the statement when either lacks the right. The set is a hashed
-- subplan, built once per statement.
CREATE FUNCTION tgsis.class_rights_filter(p_column text, p_privilege text, p_alias text DEFAULT NULL)
RETURNS text
LANGUAGE sql
IMMUTABLE
PARALLEL SAFE
AS $$
    SELECT pg_catalog.format('%s%I NOT IN (SELECT tgsis.class_denied_geoids(%L, current_user))',
                             CASE WHEN p_alias IS NOT NULL THEN pg_catalog.format('%I.', p_alias) ELSE '' END,
                             p_column, p_privilege)
$$;

COMMENT ON FUNCTION tgsis.class_rights_filter(text, text, text) IS
    'the SQL condition "<alias>.<column> NOT IN (SELECT tgsis.class_denied_geoids(<privilege>, current_user))" that the policies of the model tables and their versioned views apply';
