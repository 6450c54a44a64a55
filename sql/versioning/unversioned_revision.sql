-- tgsis.unversioned_revision(geoids): the revision rows of unversioned features are written with (0), or why they may not be written.
-- Features of a class without versioning hold one state, the one every
-- version sees: a write made "in" version v1, or while looking at an older
-- revision, would change it in DEFAULT and everywhere, so it is refused
-- (TG305) as writes to plain tables are (tgsis.plain_write_check). Keys of
-- one write must all be unversioned or all versioned: a row moved from one
-- to the other would change versions' history, or leave history behind
-- (TG300). Called by every writer of versioned storage once it found one of
-- its keys in tgsis.unversioned_features.
CREATE FUNCTION tgsis.unversioned_revision(p_geoids bigint[])
RETURNS integer
LANGUAGE plpgsql
STABLE
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_version  text := tgsis.get_working_version();
    v_viewing  integer := tgsis.get_viewing_revision();
    v_classes  text;
    v_versioned bigint;
BEGIN
    SELECT string_agg(DISTINCT u.classname, ', ' ORDER BY u.classname) INTO v_classes
      FROM tgsis.unversioned_features u WHERE u.geoid = ANY (p_geoids);
    SELECT min(k) INTO v_versioned FROM unnest(p_geoids) AS k
     WHERE k IS NOT NULL AND NOT EXISTS (SELECT FROM tgsis.unversioned_features u WHERE u.geoid = k);
    IF v_versioned IS NOT NULL THEN
        RAISE EXCEPTION 'one write cannot move rows between feature % of a versioned class and a feature of class % (not versioned)',
                v_versioned, v_classes
            USING ERRCODE = 'TG300',
                  DETAIL = 'Rows of a feature of a class without versioning have no history; a versioned feature''s rows have one.',
                  HINT = 'write the rows of each feature by itself, keeping its geoid';
    END IF;
    IF v_version = 'DEFAULT' AND (v_viewing IS NULL
                                  OR v_viewing = (SELECT v.workingrevision FROM tgsis.versions v WHERE v.versionid = 0)) THEN
        RETURN 0;
    END IF;
    IF v_version <> 'DEFAULT' THEN
        RAISE EXCEPTION 'features of class % are not versioned: a write in version % would change them in every version',
                v_classes, quote_literal(v_version)
            USING ERRCODE = 'TG305',
                  DETAIL = format('The session works in version %L (setting tgsis.version), but class %s was registered '
                                  'without versioning: its features hold one state, which every version reads. Nothing was written.',
                                  v_version, v_classes),
                  HINT = 'SELECT tgsis.goto_version(''DEFAULT'') to write them';
    END IF;
    RAISE EXCEPTION 'features of class % are not versioned: DEFAULT viewed at revision % cannot write them', v_classes, v_viewing
        USING ERRCODE = 'TG305',
              DETAIL = format('The session looks at an older revision (setting tgsis.revision); class %s holds only the '
                              'current state of its features. Nothing was written.', v_classes),
              HINT = 'SELECT tgsis.goto_version(''DEFAULT'') to write the current state';
END
$$;

COMMENT ON FUNCTION tgsis.unversioned_revision(bigint[]) IS
    'the revision (0) that rows of features of classes without versioning (tgsis.unversioned_features) are written with; TG305 unless the session is in DEFAULT''s working revision, TG300 when the geoids mix unversioned and versioned features';
