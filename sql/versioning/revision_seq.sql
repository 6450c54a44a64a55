-- The one sequence every revision number comes from. Revision 0 is DEFAULT's
-- initial revision (inserted with the schema); the sequence starts at 1.
CREATE SEQUENCE tgsis.revision_seq AS integer START WITH 1 MINVALUE 1;

COMMENT ON SEQUENCE tgsis.revision_seq IS
    'revision numbers: one sequence for all versions, so a revision number names exactly one version';
