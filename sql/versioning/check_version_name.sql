-- tgsis.check_version_name(name, what): raise TG101 unless the name is a usable version or revision name.
-- The design's names are free text (revisionname varchar(50)); tgsis takes any
-- printable text of 1 to 63 characters. 63 rather than the design's 50: the
-- rule of 0.2.0 allowed 63, and a name saved then must stay a valid name.
-- Names are never identifiers (they are values: a column, the tgsis.version
-- setting, quoted with %L wherever printed), so blanks, quotes and ; are fine.
-- Refused are what makes two names print alike or breaks a line of output:
-- control characters (C0, DEL, C1), invisible format characters (zero width,
-- bidirectional controls, soft hyphen, BOM), white space other than the plain
-- blank, and blanks at either end. Version names also may not hold @, which
-- the command line reads as VERSION@REVISION; revision names may.
CREATE FUNCTION tgsis.check_version_name(p_name text, p_what text DEFAULT 'version')
RETURNS text
LANGUAGE plpgsql
IMMUTABLE
PARALLEL SAFE
AS $$
DECLARE
    -- in UTF8 the class names the Unicode characters; other encodings hold few of them, so only ASCII's
    v_unprintable text := CASE WHEN getdatabaseencoding() = 'UTF8' THEN
        '[' || chr(1) || '-' || chr(31) || chr(127) || '-' || chr(160) || chr(173) || chr(5760)
            || chr(8192) || '-' || chr(8207) || chr(8232) || '-' || chr(8239) || chr(8287) || '-' || chr(8303)
            || chr(12288) || chr(65279) || chr(65529) || '-' || chr(65531) || ']'
        ELSE '[' || chr(1) || '-' || chr(31) || chr(127) || ']' END;
    v_pos    integer;
    v_reason text;
    v_shown  text;
BEGIN
    IF p_name IS NULL OR p_name = '' THEN
        v_reason := 'it is empty';
    ELSIF char_length(p_name) > 63 THEN
        v_reason := format('it has %s characters, names have at most 63', char_length(p_name));
    ELSE
        v_pos := strpos(p_name, substring(p_name FROM v_unprintable));
        IF v_pos > 0 THEN
            v_reason := format('character %s is U+%s, which does not print', v_pos,
                               upper(lpad(to_hex(ascii(substr(p_name, v_pos, 1))), 4, '0')));
        ELSIF p_name ~ '^ | $' THEN
            v_reason := 'it starts or ends with a blank';
        ELSIF p_what = 'version' AND strpos(p_name, '@') > 0 THEN
            v_reason := 'it holds @, which the command line reads as VERSION@REVISION';
        END IF;
    END IF;
    IF v_reason IS NOT NULL THEN
        -- the name as the message shows it: unprintable characters as <U+XXXX>, at most 60 of them
        SELECT string_agg(CASE WHEN c ~ v_unprintable THEN format('<U+%s>', upper(lpad(to_hex(ascii(c)), 4, '0')))
                               ELSE c END, '' ORDER BY i)
          INTO v_shown
          FROM regexp_split_to_table(left(p_name, 60), '') WITH ORDINALITY AS s(c, i);
        RAISE EXCEPTION '% name % is not allowed: %', p_what,
            CASE WHEN p_name IS NULL THEN 'NULL'
                 ELSE quote_literal(coalesce(v_shown, '')) || CASE WHEN char_length(p_name) > 60 THEN '...' ELSE '' END END,
            v_reason
            USING ERRCODE = 'TG101',
                  DETAIL = CASE WHEN p_what = 'version'
                                THEN 'Version names are 1 to 63 printable characters (blanks inside are fine), without @.'
                                ELSE 'Revision names are 1 to 63 printable characters (blanks inside are fine).' END;
    END IF;
    RETURN p_name;
END
$$;

COMMENT ON FUNCTION tgsis.check_version_name(text, text) IS
    'returns the name when it is a valid version or revision name (1-63 printable characters, no blank at either end; no @ in a version name), else raises TG101';
