"""Every object tgsis creates, at install and at run time, carries a COMMENT (what psql's \\d+ shows)."""

from __future__ import annotations

from typing import Any

import psycopg

import tgsis
from tgsis.db import features as F

UNCOMMENTED = """
SELECT 'column ' || n.nspname || '.' || c.relname || '.' || a.attname
  FROM pg_attribute a JOIN pg_class c ON c.oid = a.attrelid JOIN pg_namespace n ON n.oid = c.relnamespace
 WHERE n.nspname IN ('tgsis', 'public') AND c.relkind IN ('r', 'v') AND a.attnum > 0 AND NOT a.attisdropped
   AND col_description(c.oid, a.attnum) IS NULL
UNION ALL
SELECT 'relation ' || n.nspname || '.' || c.relname
  FROM pg_class c JOIN pg_namespace n ON n.oid = c.relnamespace
 WHERE n.nspname IN ('tgsis', 'public') AND c.relkind IN ('r', 'v', 'S') AND obj_description(c.oid, 'pg_class') IS NULL
UNION ALL
SELECT 'type ' || t.oid::regtype::text
  FROM pg_type t JOIN pg_namespace n ON n.oid = t.typnamespace
 WHERE n.nspname = 'tgsis' AND t.typtype IN ('r', 'm') AND obj_description(t.oid, 'pg_type') IS NULL
UNION ALL
SELECT 'function ' || p.oid::regprocedure::text
  FROM pg_proc p JOIN pg_namespace n ON n.oid = p.pronamespace
 WHERE (n.nspname = 'tgsis' OR (n.nspname = 'public' AND p.proname LIKE '%\\_ver\\_write'))
   AND obj_description(p.oid, 'pg_proc') IS NULL
   -- constructors PostgreSQL makes for a range type (tgsis.timerange): owned by the bootstrap
   -- superuser, so only a superuser may comment on them; the type's comment covers them
   AND NOT EXISTS (SELECT FROM pg_depend d WHERE d.classid = 'pg_proc'::regclass AND d.objid = p.oid
                      AND d.refclassid = 'pg_type'::regclass AND d.deptype = 'i')
ORDER BY 1"""


def test_install_classes_and_versioning_leave_nothing_uncommented(conn: psycopg.Connection[Any]) -> None:
    F.create_feature_class(
        conn, "horizons", "SURFACE", feature_properties={"creator": "text"}, cell_properties={"porosity": "float8"}
    )
    F.create_feature_class(
        conn,
        "stepped",
        "SURFACE",
        time_model="INSTANTS",
        cell_properties={"porosity": "float8"},
        instant_properties={"throw": "float8"},
    )
    tgsis.enable_feature_versioning(conn)
    F.create_feature_class(conn, "blocks", "GEOMETRYCOLLECTION", cell_properties={"facies": "int"}, alignment="CELL")
    F.create_feature_class(
        conn,
        "moving",
        "SURFACE",
        time_model="EVOLVING",
        cell_properties={"facies": "int"},
        alignment="CELL",
        instant_properties={"throw": "float8"},
    )
    conn.execute("CREATE TABLE wells (id int PRIMARY KEY, name text)")
    conn.execute("COMMENT ON TABLE wells IS 'wells'")
    conn.execute("COMMENT ON COLUMN wells.id IS 'id'")
    conn.execute("COMMENT ON COLUMN wells.name IS 'name'")
    tgsis.enable_versioning(conn, "wells", "id", "well")
    assert [r[0] for r in conn.execute(UNCOMMENTED).fetchall()] == []
    assert conn.execute("SELECT col_description('horizons_cellpros'::regclass, 3)").fetchone() == (
        "vertex property (double precision)",
    )
