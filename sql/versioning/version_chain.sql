-- tgsis.version_chain(root): the versions with a validity period at or below root, in time order; TG100 unless they form a chain.
-- A chain: each is a descendant of the one before, and the periods do not
-- overlap (a mine that revises its model after every survey keeps one).
CREATE FUNCTION tgsis.version_chain(p_root text DEFAULT 'DEFAULT')
RETURNS TABLE (name text, valid_from timestamptz, valid_to timestamptz, depth integer)
LANGUAGE plpgsql
STABLE
AS $$
DECLARE
    v_prev record;
    v_row  record;
BEGIN
    FOR v_row IN
        WITH RECURSIVE below AS (
            SELECT v.versionid, v.name, 0 AS depth, ARRAY[v.versionid] AS path
              FROM tgsis.versions v WHERE v.versionid = tgsis.version_id(p_root)
            UNION ALL
            SELECT c.versionid, c.name, b.depth + 1, b.path || c.versionid
              FROM tgsis.versions c JOIN below b ON c.parentid = b.versionid)
        SELECT b.name, v.valid_from, v.valid_to, b.depth, b.path, v.versionid
          FROM below b JOIN tgsis.versions v USING (versionid)
         WHERE v.valid_from IS NOT NULL
         ORDER BY v.valid_from
    LOOP
        IF v_prev IS NOT NULL THEN
            IF NOT v_prev.versionid = ANY (v_row.path) THEN
                RAISE EXCEPTION 'versions % and % with validity periods are not on one line of descent', v_prev.name, v_row.name
                    USING ERRCODE = 'TG100', HINT = 'a chain of beliefs is a version, its child, its grandchild, ...';
            END IF;
            IF v_prev.valid_to IS NULL OR v_prev.valid_to > v_row.valid_from THEN
                RAISE EXCEPTION 'validity periods of versions % and % overlap', v_prev.name, v_row.name
                    USING ERRCODE = 'TG100', HINT = 'end the earlier one (tgsis.set_version_validity) where the later one starts';
            END IF;
        END IF;
        name := v_row.name; valid_from := v_row.valid_from; valid_to := v_row.valid_to; depth := v_row.depth;
        RETURN NEXT;
        v_prev := v_row;
    END LOOP;
END
$$;

COMMENT ON FUNCTION tgsis.version_chain(text) IS
    'versions with a validity period at or below p_root, oldest first; raises TG100 unless they form one line of descent with periods that do not overlap';
