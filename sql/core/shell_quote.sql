-- tgsis.shell_quote(word): a text as one word of a POSIX shell command line, as Python's shlex.quote writes it.
-- Hints that print a `tgsis ...` command naming a version (a free-text name:
-- spaces, quotes, $) would otherwise tell the user a command that the shell
-- splits or expands: 'my version' stays one argument. A word of only
-- letters, digits and @%+=:,./-_ is left as it is; the empty text is ''.
CREATE FUNCTION tgsis.shell_quote(p_word text)
RETURNS text
LANGUAGE sql
IMMUTABLE
STRICT
PARALLEL SAFE
AS $$
    SELECT CASE WHEN p_word = '' THEN ''''''
                WHEN p_word ~ '^[A-Za-z0-9_@%+=:,./-]+$' THEN p_word
                ELSE '''' || pg_catalog.replace(p_word, '''', '''"''"''') || '''' END
$$;

COMMENT ON FUNCTION tgsis.shell_quote(text) IS
    'a text as one word of a POSIX shell command line, exactly as Python''s shlex.quote writes it: what the hints that print a tgsis command put around a version name';
