-- tgsis.version_believed_at(at, root): the version of the chain below root believed true at a moment (NULL: none).
CREATE FUNCTION tgsis.version_believed_at(p_at timestamptz, p_root text DEFAULT 'DEFAULT')
RETURNS text
LANGUAGE sql
STABLE
AS $$
    SELECT c.name FROM tgsis.version_chain(p_root) AS c
     WHERE c.valid_from <= p_at AND (c.valid_to IS NULL OR p_at < c.valid_to)
$$;

COMMENT ON FUNCTION tgsis.version_believed_at(timestamptz, text) IS
    'name of the version believed true at p_at in the chain of versions with validity periods below p_root (tgsis.version_chain); NULL when none';
