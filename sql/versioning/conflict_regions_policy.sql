-- tgsis.conflict_regions' row-level security: a role reads the regions of a feature only when it may read the feature's class.
-- A region holds its vertex and cell ids, its box, how far each side moved it and, for the
-- average and manual solutions, the region's rows themselves (coordinates and values): no more
-- readable than the mesh's own rows in tgsis.vrtx and the simplex tables, which every class shares
-- and whose policies keep from a role the rows of the classes it may not read
-- (tgsis.protect_model_tables). The same set (tgsis.class_denied_geoids) filters the regions of
-- features (objectkey: the geoid as text). That the object conflicts stays readable in
-- tgsis.conflicts, as before. The functions that write the regions run as tgsis's owner, whom the
-- policy spares; so are superusers. A separate file from the table's: the policy needs
-- tgsis.class_denied_geoids, which an upgrade creates after its new tables.
ALTER TABLE tgsis.conflict_regions ENABLE ROW LEVEL SECURITY;

CREATE POLICY tgsis_class_read ON tgsis.conflict_regions FOR SELECT
    USING (objectclass <> 'feature'
           OR objectkey NOT IN (SELECT d::text FROM tgsis.class_denied_geoids('SELECT', current_user) AS d));
