-- tgsis.check_class_write(geoids, privilege): refuse (42501) to write model rows of features of a class the calling role may not change.
-- The definer code that writes the shared model tables for a role — the
-- INSTEAD OF triggers of their versioned views, merges, set-based deletes —
-- runs as tgsis's owner, whom row-level security spares: it calls this first,
-- with the geoids it is about to write, so that per-class rights hold there as
-- they do for the role's own statements (tgsis.class_denied_geoids, whose
-- rule it applies: a row is the class's whose feature table holds its geoid,
-- in any revision, or holds the collection owning it). p_privilege:
-- 'UPDATE' for inserting and changing rows of a feature, 'UPDATE, DELETE' for
-- deleting them. The views call it per row, so it probes rather than
-- collecting: one has_table_privilege per class, and only for the classes the
-- role lacks the right on, one index probe of their feature table for the
-- given geoids (and one of tgsis.geometry for the collections owning them).
-- SECURITY DEFINER: it reads the feature tables the role may not read; it
-- says only whether the given geoids are in them, and names the class.
CREATE FUNCTION tgsis.check_class_write(p_geoids bigint[], p_privilege text DEFAULT 'UPDATE')
RETURNS void
LANGUAGE plpgsql
STABLE
SECURITY DEFINER
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_role  name := tgsis.calling_role();
    v_class record;
    v_ids   bigint[];
    v_geoid bigint;
BEGIN
    IF p_privilege IS NULL OR p_privilege NOT IN ('UPDATE', 'UPDATE, DELETE') THEN
        RAISE EXCEPTION 'privilege % is not one writes of model rows are checked for', coalesce(quote_literal(p_privilege), 'NULL')
            USING ERRCODE = 'TG100', HINT = 'p_privilege => ''UPDATE'' or ''UPDATE, DELETE''';
    END IF;
    FOR v_class IN
        SELECT c.classname, tgsis.class_storage(t.rel) AS storage
          FROM tgsis.catalog c
         CROSS JOIN LATERAL (SELECT to_regclass(format('%I.%I', c.schemaname, c.featuretable)) AS rel) t
         WHERE t.rel IS NOT NULL AND NOT pg_catalog.has_table_privilege(v_role, t.rel, p_privilege)
         ORDER BY c.classname
    LOOP
        IF v_ids IS NULL THEN  -- the geoids and the collections owning them, once
            EXECUTE format('SELECT array_agg(DISTINCT g.collection) FROM %s g WHERE g.geoid = ANY ($1) AND g.collection IS NOT NULL',
                           tgsis.class_storage('tgsis.geometry'))
               INTO v_ids USING p_geoids;
            v_ids := p_geoids || coalesce(v_ids, '{}');
        END IF;
        EXECUTE format('SELECT f._geoid FROM %s f WHERE f._geoid = ANY ($1) LIMIT 1', v_class.storage) INTO v_geoid USING v_ids;
        IF v_geoid IS NOT NULL THEN
            RAISE EXCEPTION 'role % may not change feature % of class %', quote_ident(v_role), v_geoid, quote_literal(v_class.classname)
                USING ERRCODE = 'insufficient_privilege',
                      DETAIL = format('Its vertices, cells and other rows in the model tables (tgsis.vrtx, tgsis.trgl, ...) '
                                      'follow the rights on the class''s table; the role lacks %s there.', p_privilege),
                      HINT = format('a DBA may run: GRANT %s ON %s TO %I', split_part(p_privilege, ',', 1),
                                    (SELECT format('%I.%I', c.schemaname, c.featuretable) FROM tgsis.catalog c
                                      WHERE c.classname = v_class.classname), v_role);
        END IF;
    END LOOP;
END
$$;

COMMENT ON FUNCTION tgsis.check_class_write(bigint[], text) IS
    'raise 42501 when one of the geoids belongs to a feature class (or to a collection of one) on whose feature table the calling role lacks p_privilege (UPDATE; UPDATE, DELETE for deletes); called by the definer code writing model tables for a role';
