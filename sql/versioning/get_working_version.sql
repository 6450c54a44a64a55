-- tgsis.get_working_version(): name of the session's working version (setting tgsis.version; DEFAULT when unset).
CREATE FUNCTION tgsis.get_working_version()
RETURNS text
LANGUAGE sql
STABLE
PARALLEL SAFE
AS $$
    SELECT coalesce(nullif(current_setting('tgsis.version', true), ''), 'DEFAULT')
$$;

COMMENT ON FUNCTION tgsis.get_working_version() IS
    'name of the session''s working version: the setting tgsis.version (set by goto_version, or SET [LOCAL] tgsis.version), DEFAULT when unset';
