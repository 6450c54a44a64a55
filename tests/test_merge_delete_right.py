"""One SQLSTATE for a merge refused for want of the DELETE right on a property view (issue 39).

The merges of a surface at instants (model 2) write a property view's rows as the Python client's statement does:
PostgreSQL refuses its DELETE with 42501 (insufficient_privilege), and the psql merge asks the same right first
(tgsis.check_merge_table_write, 42501). The merges of a model-1 mesh delete rows through
tgsis.delete_object_rows, which refused the same missing right with TG002: one missing right, two codes by data
model. tgsis.close_object_rows now refuses it as PostgreSQL refuses a DELETE of the view: 42501, which
tgsis.MissingPrivilegeError maps as it maps TG002 (docs/errors.md).
"""

from __future__ import annotations

from typing import Any

import psycopg
import pytest
from psycopg import sql

import tgsis
from tests.merge_data import move as move1
from tests.test_merge_instants import CHILD_SHIFT
from tests.test_sql_merge_write import everything

Conn = psycopg.Connection[Any]


@pytest.mark.parametrize("alignment", ["VERTEX", "CELL"])
def test_a_model1_merge_without_delete_on_a_property_view_is_refused_42501_by_both_merges(
    conn: Conn, fault_clone: int, db_dsn: str, alignment: str
) -> None:
    """The parent changed property values of the fault; the version moved vertices. The editor may merge but not
    DELETE from the class's property view: the Python merge and the psql merge refuse with 42501, the code the
    merges of model 2 give for the same role, writing nothing."""
    from tests.roles import login_roles

    geoid = fault_clone
    row = conn.execute(
        "SELECT CASE WHEN proalignment = %s THEN cellprotable ELSE otherprotable END FROM tgsis.catalog"
        " WHERE classname = 'faults'",
        (alignment,),
    ).fetchone()
    assert row is not None and row[0]
    table, column = str(row[0]), "porosity" if alignment == "VERTEX" else "facies"
    with tgsis.in_version(conn, "DEFAULT"):
        conn.execute(
            sql.SQL("UPDATE {} SET {} = {} + 1 WHERE _geoid = %s AND _idx BETWEEN 130 AND 133").format(
                sql.Identifier(table), sql.Identifier(column), sql.Identifier(column)
            ),
            (geoid,),
        )
    conn.commit()
    move1(conn, "e1", geoid, range(0, 3), CHILD_SHIFT)
    with login_roles(db_dsn, {"ed": "tgsis_editor"}) as made:
        tgsis.grant_version(conn, "e1", "all", made.name("ed"))
        tgsis.grant_version(conn, "DEFAULT", "merge", made.name("ed"))
        conn.execute(sql.SQL("REVOKE DELETE ON {} FROM tgsis_editor").format(sql.Identifier(table)))
        conn.commit()
        before = everything(conn)
        conn.commit()
        session = made.connect("ed")
        with pytest.raises(tgsis.MissingPrivilegeError) as python:
            tgsis.merge_version(session, "e1")
        session.rollback()
        with pytest.raises(psycopg.errors.InsufficientPrivilege) as caught:
            session.execute("SELECT tgsis.merge_version('e1')")
        session.rollback()
        assert (python.value.sqlstate, caught.value.sqlstate) == ("42501", "42501"), str(caught.value)
        assert table in str(caught.value)
        assert everything(conn) == before
        conn.commit()


def test_delete_object_rows_without_the_delete_right_is_refused_as_postgresql_refuses_the_view(
    conn: Conn, fault_clone: int, db_dsn: str
) -> None:
    """The same right asked of a plain DELETE of the view and of tgsis.delete_object_rows: one code, 42501."""
    from tests.roles import login_roles

    geoid = fault_clone
    table = conn.execute("SELECT cellprotable FROM tgsis.catalog WHERE classname = 'faults'").fetchone()
    assert table is not None and table[0]
    with login_roles(db_dsn, {"ed": "tgsis_editor"}) as made:
        tgsis.grant_version(conn, "e1", "all", made.name("ed"))
        conn.execute(sql.SQL("REVOKE DELETE ON {} FROM tgsis_editor").format(sql.Identifier(table[0])))
        conn.commit()
        session = made.connect("ed")
        codes = []
        for statement, args in (
            (sql.SQL("DELETE FROM {} WHERE _geoid = %s AND _idx = 1").format(sql.Identifier(table[0])), (geoid,)),
            (
                sql.SQL("SELECT tgsis.delete_object_rows('public', %s, '_geoid', %s, '_idx', '{1}')"),
                (table[0], [geoid]),
            ),
        ):
            with pytest.raises(psycopg.Error) as caught, tgsis.in_version(session, "e1"):
                session.execute(statement, args)
            codes.append(caught.value.sqlstate)
            session.rollback()
        assert codes == ["42501", "42501"], codes
