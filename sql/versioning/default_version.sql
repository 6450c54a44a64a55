-- The root version DEFAULT with its initial revision 0, created with the schema.
INSERT INTO tgsis.versions (versionid, name, parentid, initrevision, workingrevision, workingset, description)
VALUES (0, 'DEFAULT', NULL, NULL, 0, '{0}', 'the root version');
INSERT INTO tgsis.revisions (revision, versionid) VALUES (0, 0);
