"""Our SQLSTATEs: one table in SQL, one exception tree in Python, one page of docs."""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import psycopg
import pytest

import tgsis
from tgsis import errors

DOCS = Path(__file__).resolve().parents[1] / "docs" / "errors.md"


def _camel(name: str) -> str:
    return "".join(part.capitalize() for part in name.split("_")) + "Error"


def _sql_codes(conn: psycopg.Connection[Any]) -> dict[str, str]:
    return dict(conn.execute("SELECT sqlstate, name FROM tgsis.error_codes").fetchall())


def test_every_sql_code_has_its_python_class(conn: psycopg.Connection[Any]) -> None:
    codes = _sql_codes(conn)
    assert len(codes) >= 10
    for sqlstate, name in codes.items():
        cls = errors.class_for_sqlstate(sqlstate)
        assert cls.code == sqlstate, f"{sqlstate} ({name}) maps to {cls.__name__}"
        expected = "Error" if sqlstate == "TG000" else _camel(name)
        assert cls.__name__ == expected
        assert getattr(tgsis, expected) is cls, f"{expected} is not exported by tgsis"


def test_every_python_code_is_in_sql(conn: psycopg.Connection[Any]) -> None:
    codes = _sql_codes(conn)
    classes: list[type[errors.Error]] = [errors.Error, *errors._all_subclasses(errors.Error)]
    python_codes = {c.code for c in classes if c.code}
    assert python_codes == set(codes)


def test_docs_list_exactly_the_sql_codes(conn: psycopg.Connection[Any]) -> None:
    documented = dict(re.findall(r"^\| `(TG\d{3})` \| (\w+) \|", DOCS.read_text(), re.MULTILINE))
    assert documented == _sql_codes(conn)


@pytest.mark.parametrize(
    ("sqlstate", "cls"),
    [
        ("TG101", tgsis.InvalidNameError),
        ("TG1ZZ", tgsis.InvalidInputError),  # unknown code: class of its area
        ("TG2ZZ", tgsis.NotFoundError),
        ("TG9ZZ", tgsis.Error),
        ("TG000", tgsis.Error),
        ("42501", tgsis.MissingPrivilegeError),
        ("40001", tgsis.ConcurrentChangeError),  # a write through a view that read a row changed meanwhile
        ("40P01", tgsis.ConcurrentChangeError),
        ("22012", tgsis.DatabaseError),
    ],
)
def test_server_errors_become_tgsis_exceptions(
    conn: psycopg.Connection[Any], sqlstate: str, cls: type[tgsis.Error]
) -> None:
    raise_it = (
        "DO $$ BEGIN RAISE EXCEPTION 'bad %', 'thing' USING ERRCODE = '"
        + sqlstate
        + "', DETAIL = 'the detail', HINT = 'the hint'; END $$"
    )
    with pytest.raises(tgsis.Error) as info, errors.reraise():
        conn.execute(raise_it)
    assert type(info.value) is cls
    assert info.value.sqlstate == sqlstate
    assert info.value.message == "bad thing"
    assert (info.value.detail, info.value.hint) == ("the detail", "the hint")
    assert isinstance(info.value.__cause__, psycopg.Error)
    assert str(info.value) == "bad thing\nDETAIL: the detail\nHINT: the hint"


def test_input_errors_are_value_errors_and_not_found_is_a_lookup_error() -> None:
    assert issubclass(tgsis.InvalidGeometryError, ValueError)
    assert issubclass(tgsis.NotFoundError, LookupError)
    err = tgsis.InvalidGeometryError("vertex 3 has a NaN coordinate")
    assert err.sqlstate == "TG102" and str(err) == "vertex 3 has a NaN coordinate"


def test_connection_failures_are_database_errors() -> None:
    with pytest.raises(tgsis.DatabaseError) as info:
        tgsis.connect("host=/nonexistent-socket-dir port=1 dbname=x connect_timeout=2")
    assert "nonexistent-socket-dir" in str(info.value)


def test_a_write_in_a_read_only_transaction_says_where_to_write(conn: psycopg.Connection[Any]) -> None:
    """25006 carries no hint from the server; tgsis gives one (the hot standby's case: tests/test_hot_standby.py)."""
    tgsis.create_feature_class(conn, "rocks", "SURFACE")
    conn.commit()
    conn.execute("SET default_transaction_read_only = on")
    conn.commit()
    surface = tgsis.Surface([[0.0, 0, 0], [1, 0, 0.5], [0, 1, 0.25]], [[0, 1, 2]])
    with pytest.raises(tgsis.DatabaseError, match="read-only transaction") as caught:
        tgsis.insert_feature(conn, "rocks", surface)
    assert caught.value.sqlstate == "25006"
    assert "write on the primary" in (caught.value.hint or "") and "default_transaction_read_only" in (
        caught.value.hint or ""
    )
    conn.rollback()
    conn.execute("SET default_transaction_read_only = off")
    conn.commit()
    assert tgsis.fetch_features(conn, "rocks") == []  # nothing stored
