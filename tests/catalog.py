"""A comparable description of the tgsis objects in a database (for tests)."""

from __future__ import annotations

from typing import Any

import psycopg

_QUERIES = {
    "schema": """
        SELECT n.nspname, n.nspacl::text, obj_description(n.oid, 'pg_namespace')
          FROM pg_namespace n WHERE n.nspname = 'tgsis'""",
    "relation": """
        SELECT c.relname, c.relkind, c.relacl::text, obj_description(c.oid, 'pg_class'),
               pg_get_userbyid(c.relowner)
          FROM pg_class c WHERE c.relnamespace = 'tgsis'::regnamespace""",
    "column": """
        SELECT c.relname, a.attname, format_type(a.atttypid, a.atttypmod), a.attnotnull,
               pg_get_expr(d.adbin, d.adrelid), col_description(c.oid, a.attnum), a.attnum
          FROM pg_attribute a
          JOIN pg_class c ON c.oid = a.attrelid
          LEFT JOIN pg_attrdef d ON d.adrelid = a.attrelid AND d.adnum = a.attnum
         WHERE c.relnamespace = 'tgsis'::regnamespace AND a.attnum > 0 AND NOT a.attisdropped""",
    "constraint": """
        SELECT conrelid::regclass::text, conname, pg_get_constraintdef(oid)
          FROM pg_constraint WHERE connamespace = 'tgsis'::regnamespace""",
    "index": """
        SELECT indexrelid::regclass::text, pg_get_indexdef(indexrelid)
          FROM pg_index i JOIN pg_class c ON c.oid = i.indexrelid
         WHERE c.relnamespace = 'tgsis'::regnamespace""",
    "function": """
        SELECT p.oid::regprocedure::text, pg_get_functiondef(p.oid), p.proacl::text,
               obj_description(p.oid, 'pg_proc')
          FROM pg_proc p WHERE p.pronamespace = 'tgsis'::regnamespace AND p.prokind <> 'a'""",
    "view": """
        SELECT c.relname, pg_get_viewdef(c.oid)
          FROM pg_class c WHERE c.relnamespace = 'tgsis'::regnamespace AND c.relkind IN ('v', 'm')""",
    "trigger": """
        SELECT t.tgrelid::regclass::text, t.tgname, pg_get_triggerdef(t.oid)
          FROM pg_trigger t JOIN pg_class c ON c.oid = t.tgrelid
         WHERE c.relnamespace = 'tgsis'::regnamespace AND NOT t.tgisinternal""",
    "type": """
        SELECT t.typname, t.typtype FROM pg_type t
         WHERE t.typnamespace = 'tgsis'::regnamespace AND t.typrelid = 0 AND t.typelem = 0""",
    "role": """
        SELECT r.rolname, r.rolcanlogin, array(
                 SELECT g.rolname FROM pg_auth_members m JOIN pg_roles g ON g.oid = m.roleid
                  WHERE m.member = r.oid ORDER BY 1)::text
          FROM pg_roles r WHERE r.rolname LIKE 'tgsis\\_%'""",
    "error_code": "SELECT sqlstate, name, area, description FROM tgsis.error_codes",
}


def describe_tgsis_objects(conn: psycopg.Connection[Any], schema: str = "tgsis") -> dict[str, list[tuple[str, ...]]]:
    """Every object of ``schema`` (tgsis) with its definition, comments and grants, sorted per kind."""
    return {
        kind: sorted(
            tuple("" if v is None else str(v) for v in row)
            for row in conn.execute(query.replace("'tgsis'", f"'{schema}'")).fetchall()
        )
        for kind, query in _QUERIES.items()
        if schema == "tgsis" or kind not in ("schema", "role", "error_code")
    }
