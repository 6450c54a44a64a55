"""The CHECK of a vector added to a class in chunks is named as the row table would name it (plan M, X item 4).

``tgsis.add_property`` adds a vector property's CHECK to the row definition (``<table>_shape``) of a class in
chunks under the name PostgreSQL gives it on the row storage (``<table>_<column>_check``, ``<table>_ver...``
when versioned), so that the writers of chunks name the same constraint as rows do (23514). Two cases the
copy of the rule missed (last session, V2): a name already taken in the schema, where PostgreSQL tries
``check1``, ``check2``..., and a name at the length limit with the longer label. (A non-ASCII name cannot
arise: class and property names are ASCII letters, digits and underscores, TG101; the copy shortens in bytes
and cuts back to a whole character as PostgreSQL does all the same.) Each is compared with a twin class kept
in rows, the same statements on both, versioned or not.
"""

from __future__ import annotations

from typing import Any

import psycopg
import pytest
from psycopg.types.json import Jsonb

import tgsis
from tests.storage_data import classes_as_rows

Conn = psycopg.Connection[Any]


@pytest.fixture(autouse=True)
def _classes_as_rows(db_dsn: str) -> None:
    """The classes these tests make start as rows: they switch them to chunks themselves, or compare with a rows
    twin (docs/storage.md, "Property chunks by default: the rule")."""
    classes_as_rows(db_dsn)


#: twins of names of one length, so that the shortened names compare once the twin's name is replaced
TWINS = {"rows": "twr", "chunks": "twc"}
LONG = "_" + "a" * 20  # a class name long enough to meet the limit with a long property name


def _add(conn: Conn, name: str, prop: str, size: int = 2) -> None:
    spec = Jsonb({"name": prop, "type": "double precision", "size": size})
    conn.execute("SELECT tgsis.add_property(%s, 'cell', %s)", (name, spec))


def _names(conn: Conn, name: str, table: str) -> list[str]:
    """The CHECK constraints of the class's row definition (its row table, or the shape when in chunks) but the
    shape's own, the twin's name replaced by ``X``."""
    relation = f"public.{table}"
    shape = conn.execute("SELECT tgsis.row_shape(%s)::oid", (relation,)).fetchone()
    assert shape is not None
    rows = conn.execute(
        "SELECT conname FROM pg_constraint WHERE conrelid = %s AND contype = 'c' AND conname NOT LIKE '%%holds_no_rows'"
        " ORDER BY conname",
        shape,
    ).fetchall()
    return [r[0].replace(name, "X") for r in rows]


@pytest.mark.parametrize("versioned", [False, True], ids=["unversioned", "versioned"])
def test_a_vector_s_check_is_named_as_the_row_table_names_it(conn: Conn, versioned: bool) -> None:
    for name in TWINS.values():
        for cls in (name, name + LONG):
            tgsis.create_feature_class(conn, cls, "GEOMETRYCOLLECTION", cell_properties=[("t", "real")])
        # a constraint of the schema taking the name the next vector's CHECK would get
        taken = f"{name}_cellpros{'_ver' if versioned else ''}_c_check"
        conn.execute(f'CREATE TABLE public.{name}_other (v integer CONSTRAINT "{taken}" CHECK (v > 0))')
    conn.commit()
    if versioned:
        tgsis.enable_feature_versioning(conn)
        conn.commit()
    for cls in (TWINS["chunks"], TWINS["chunks"] + LONG):
        conn.execute("SELECT tgsis.store_class_in_chunks(%s)", (cls,))
    conn.commit()
    longest = "p" * 50  # shortened with the class's 33-byte table name, the longer first
    for name in TWINS.values():
        _add(conn, name, "a")
        conn.execute("SELECT tgsis.rename_property(%s, 'a', 'b')", (name,))
        _add(conn, name, "a")  # <table>_a_check is the renamed b's: check1
        _add(conn, name, "c")  # taken by another table's constraint: check1
        conn.execute("SELECT tgsis.rename_property(%s, 'a', 'd')", (name,))
        _add(conn, name, "a")  # check and check1 both taken: check2
        _add(conn, name + LONG, longest)
        _add(conn, name + LONG, longest[:-1] + "q")  # the same shortened name: check1 (one byte more of label)
    conn.commit()
    got = {
        storage: (_names(conn, name, f"{name}_cellpros"), _names(conn, name, f"{name}{LONG}_cellpros"))
        for storage, name in TWINS.items()
    }
    assert got["chunks"] == got["rows"]
    short, long = got["rows"]
    ver = "_ver" if versioned else ""
    assert short == sorted(f"X_cellpros{ver}_{c}" for c in ("a_check", "a_check1", "a_check2", "c_check1")), short
    assert all(len(n.replace("X", TWINS["rows"]).encode()) <= 63 for n in long) and len(long) == 2, long
    # the chunks' writers name the same constraint as the row table does
    answers = []
    for name in TWINS.values():
        with pytest.raises(psycopg.errors.CheckViolation) as caught:
            conn.execute(f"INSERT INTO public.{name}{LONG}_cellpros (_geoid, _idx, {longest}) VALUES (1, 1, '{{1}}')")
        conn.rollback()
        answers.append(str(caught.value.diag.constraint_name).replace(name, "X"))
    assert answers[0] == answers[1] and answers[0] in long, answers
