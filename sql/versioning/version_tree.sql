-- The version tree for people: one row per version in depth-first order, with
-- its parent, depth, revisions and saved (named) revisions.
CREATE VIEW tgsis.version_tree AS
WITH RECURSIVE walk AS (
    SELECT v.versionid, v.name, NULL::text AS parent, 0 AS depth, ARRAY[v.name] AS path
      FROM tgsis.versions v WHERE v.parentid IS NULL
    UNION ALL
    SELECT c.versionid, c.name, w.name, w.depth + 1, w.path || c.name
      FROM tgsis.versions c JOIN walk w ON c.parentid = w.versionid
)
SELECT w.name, w.parent, w.depth, v.initrevision, v.workingrevision,
       (SELECT array_agg(r.revision ORDER BY r.revision) FROM tgsis.revisions r WHERE r.versionid = v.versionid) AS revisions,
       (SELECT coalesce(jsonb_object_agg(r.name, r.revision ORDER BY r.revision), '{}')
          FROM tgsis.revisions r WHERE r.versionid = v.versionid AND r.name IS NOT NULL) AS saved,
       v.owner, v.created_at, v.description, w.path
  FROM walk w JOIN tgsis.versions v ON v.versionid = w.versionid
 ORDER BY w.path;

COMMENT ON VIEW tgsis.version_tree IS 'versions in depth-first order with parent, depth, own revisions and saved revisions';
COMMENT ON COLUMN tgsis.version_tree.name IS 'version name';
COMMENT ON COLUMN tgsis.version_tree.parent IS 'parent version (NULL for DEFAULT)';
COMMENT ON COLUMN tgsis.version_tree.depth IS 'distance from DEFAULT';
COMMENT ON COLUMN tgsis.version_tree.initrevision IS 'parent''s working revision when the version was created';
COMMENT ON COLUMN tgsis.version_tree.workingrevision IS 'the revision its changes are labelled with';
COMMENT ON COLUMN tgsis.version_tree.revisions IS 'its own revisions, ascending';
COMMENT ON COLUMN tgsis.version_tree.saved IS 'saved revisions: {"name": revision}';
COMMENT ON COLUMN tgsis.version_tree.owner IS 'role that created it';
COMMENT ON COLUMN tgsis.version_tree.created_at IS 'when it was created';
COMMENT ON COLUMN tgsis.version_tree.description IS 'free text';
COMMENT ON COLUMN tgsis.version_tree.path IS 'names from DEFAULT down to it (the sort key)';
