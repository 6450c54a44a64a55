-- tgsis.or_list(words): 'A, B or C' — a list of choices for a message, from the rows that define them.
-- Messages that list what is allowed (geotypes, time models) build the list
-- from the registry, so they stay right when a data model is added.
CREATE FUNCTION tgsis.or_list(p_words text[])
RETURNS text
LANGUAGE sql
IMMUTABLE
PARALLEL SAFE
AS $$
    SELECT CASE WHEN cardinality(p_words) IS NULL OR cardinality(p_words) = 0 THEN ''
                WHEN cardinality(p_words) = 1 THEN p_words[1]
                ELSE array_to_string(p_words[1:cardinality(p_words) - 1], ', ') || ' or ' || p_words[cardinality(p_words)]
           END
$$;

COMMENT ON FUNCTION tgsis.or_list(text[]) IS 'the words as a list of choices for a message: ''A, B or C'' ('''' for none)';
