-- tgsis.check_no_unsolved_conflicts(version, action): recompute a version's conflicts; TG302 naming the unsolved ones.
CREATE FUNCTION tgsis.check_no_unsolved_conflicts(p_version text, p_action text)
RETURNS void
LANGUAGE plpgsql
VOLATILE
AS $$
DECLARE
    v_count integer;
    v_list  text;
BEGIN
    SELECT count(*), string_agg(format('%s %s (%s)', objectclass, objectkey,
                                       coalesce(nullif(array_to_string(conflicttype, ', '), ''), 'different tables')),
                                '; ' ORDER BY objectclass, objectkey)
      INTO v_count, v_list
      FROM tgsis.find_conflicts(p_version) WHERE solution = 'unsolved';
    IF v_count > 0 THEN
        RAISE EXCEPTION '% of version % refused: % unsolved conflict(s): %', p_action, quote_literal(p_version), v_count, v_list
            USING ERRCODE = 'TG302',
                  HINT = format('record a solution for each: SELECT tgsis.resolve_conflict(%L, class, key, ''parent''|''child''|''manual'')',
                                p_version);
    END IF;
END
$$;

COMMENT ON FUNCTION tgsis.check_no_unsolved_conflicts(text, text) IS
    'recompute the conflicts of a version and raise TG302 naming the unsolved ones (before a merge or refresh)';
