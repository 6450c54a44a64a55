-- tgsis.check_class_write(geoids, privilege): refuse (42501) to write model rows of features of a class the calling role may not change.
-- The definer code that writes the shared model tables for a role — the
-- INSTEAD OF triggers of their versioned views, merges, set-based deletes —
-- runs as tgsis's owner, whom row-level security spares: it calls this first,
-- with the geoids it is about to write, so that per-class rights hold there as
-- they do for the role's own statements (tgsis.class_denied_geoids). p_privilege:
-- 'UPDATE' for inserting and changing rows of a feature, 'UPDATE, DELETE' for
-- deleting them. Cheap when the role may write every class (one
-- has_table_privilege per class), as it is called per row by the views.
CREATE FUNCTION tgsis.check_class_write(p_geoids bigint[], p_privilege text DEFAULT 'UPDATE')
RETURNS void
LANGUAGE plpgsql
STABLE
AS $$
DECLARE
    v_geoid bigint;
    v_class text;
BEGIN
    SELECT k INTO v_geoid
      FROM pg_catalog.unnest(p_geoids) AS k
     WHERE k IN (SELECT tgsis.class_denied_geoids(p_privilege))
     LIMIT 1;
    IF v_geoid IS NOT NULL THEN
        v_class := tgsis.class_of_geoid(v_geoid);
        RAISE EXCEPTION 'role % may not change feature % of class %', quote_ident(tgsis.calling_role()), v_geoid,
                        coalesce(quote_literal(v_class), '(unknown)')
            USING ERRCODE = 'insufficient_privilege',
                  DETAIL = format('Its vertices, cells and other rows in the model tables (tgsis.vrtx, tgsis.trgl, ...) '
                                  'follow the rights on the class''s table; the role lacks %s there.', p_privilege),
                  HINT = 'a DBA may run: GRANT ' || p_privilege || ' ON <the class''s table> TO ' || quote_ident(tgsis.calling_role());
    END IF;
END
$$;

COMMENT ON FUNCTION tgsis.check_class_write(bigint[], text) IS
    'raise 42501 when one of the geoids belongs to a feature class (or to a collection of one) on whose feature table the calling role lacks p_privilege (UPDATE; UPDATE, DELETE for deletes); called by the definer code writing model tables for a role';
