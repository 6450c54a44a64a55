-- tgsis.class_denied_geoids(privilege, role): the geometries of the feature classes whose table the calling role (or the role given) lacks a right on.
-- Per-class rights (docs/security.md) must hold at the model tables too: the
-- vertices, cells and rows of every model that a class's features own live in
-- tables every class shares (tgsis.geometry, tgsis.vrtx, tgsis.trgl, ...),
-- keyed by geoid. A model row belongs to the class whose feature table holds
-- its geoid (in any revision: an old revision's rows stay the class's), or to
-- the class of the collection that owns it (tgsis.geometry.collection); a
-- geometry of no class is everybody's who may read the model table. The
-- row-level security policies of the model tables (tgsis.protect_model_tables)
-- keep a row from a role when its geoid is in this set, and the definer code
-- that writes model rows for a role (the versioned views' triggers, merges,
-- set-based deletes) refuses such rows (tgsis.check_class_write).
-- Why a set per statement rather than a test per row: the policies use it as
-- "geoid NOT IN (SELECT ...)", a hashed subplan that PostgreSQL builds once
-- per query and probes per row; a role with every right gets the empty set
-- after one has_table_privilege per class. SECURITY DEFINER: it reads the
-- feature tables of the classes the caller may not read (their geoids only),
-- as tgsis's owner, who owns them; which rights count is the calling role's
-- (tgsis.calling_role(), the same inside definer functions) and p_role's:
-- a class is denied when either lacks the right. The policies and the
-- versioned views pass current_user, the role their statement runs as: in a
-- SECURITY DEFINER function of another role (say a lesser one that an admin
-- calls) that is the function's owner, whose rights must bound what the
-- function reads, as PostgreSQL's own privileges do. A role may pass any
-- role: it only adds classes to the caller's own set, whose tables the
-- caller may read anyway (so no geoid is learnt that was hidden). p_privilege is
-- what has_table_privilege takes: 'SELECT' (reading), 'UPDATE' (changing a
-- feature's geometry), 'UPDATE, DELETE' (deleting its rows: either right).
-- Plain PL/pgSQL on purpose: it is created before the tables it reads
-- (tgsis.create_storage creates the policies naming it).
CREATE FUNCTION tgsis.class_denied_geoids(p_privilege text, p_role name DEFAULT NULL)
RETURNS SETOF bigint
LANGUAGE plpgsql
STABLE
PARALLEL SAFE
SECURITY DEFINER
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_role     name := tgsis.calling_role();
    v_sources  text;
    v_geometry regclass := tgsis.class_storage('tgsis.geometry');
BEGIN
    IF p_privilege IS NULL OR p_privilege NOT IN ('SELECT', 'UPDATE', 'UPDATE, DELETE') THEN
        RAISE EXCEPTION 'privilege % is not one per-class rights are checked for', coalesce(quote_literal(p_privilege), 'NULL')
            USING ERRCODE = 'TG100', HINT = 'p_privilege => ''SELECT'', ''UPDATE'' or ''UPDATE, DELETE''';
    END IF;
    -- the storage of the feature table of each class the role may not read/write (the table, or <table>_ver)
    SELECT string_agg(format('SELECT f._geoid FROM %s f', tgsis.class_storage(t.rel)), ' UNION ALL ')
      INTO v_sources
      FROM tgsis.catalog c
     CROSS JOIN LATERAL (SELECT to_regclass(format('%I.%I', c.schemaname, c.featuretable)) AS rel) t
     WHERE t.rel IS NOT NULL
       AND (NOT pg_catalog.has_table_privilege(v_role, t.rel, p_privilege)
            OR (p_role IS NOT NULL AND p_role <> v_role AND NOT pg_catalog.has_table_privilege(p_role, t.rel, p_privilege)));
    IF v_sources IS NULL THEN
        RETURN;
    END IF;
    -- a collection's members are its class's (the members it owns: collection = its geoid)
    RETURN QUERY EXECUTE format('WITH d AS MATERIALIZED (%s) SELECT d._geoid FROM d '
                                'UNION SELECT g.geoid FROM %s g WHERE g.collection IN (SELECT d._geoid FROM d)',
                                v_sources, v_geometry);
END
$$;

COMMENT ON FUNCTION tgsis.class_denied_geoids(text, name) IS
    'the geoids of the features (and the collection members they own) of the feature classes on whose feature table the calling role, or p_role (the policies and views pass current_user), lacks p_privilege (SELECT, UPDATE, or UPDATE, DELETE: either); what the row-level security policies of the model tables and the versioned views keep from the role';
