"""Valid time of versions: the model believed at a date, along a chain of versions."""

from __future__ import annotations

from datetime import datetime, timezone
from typing import Any

import psycopg
import pytest

import tgsis
from tgsis.cli import main

Conn = psycopg.Connection[Any]


def _day(text: str) -> datetime:
    return datetime.fromisoformat(text).replace(tzinfo=timezone.utc)


@pytest.fixture
def surveys(conn: Conn) -> Conn:
    """A mine's model revised after each survey: DEFAULT -> s1 -> s2 -> s3, and a scratch version off the line."""
    tgsis.create_version(conn, "s1")
    tgsis.create_version(conn, "s2", "s1")
    tgsis.create_version(conn, "s3", "s2")
    tgsis.create_version(conn, "scratch", "s1")
    tgsis.set_version_validity(conn, "s1", _day("2024-01-01"), _day("2024-06-01"))
    tgsis.set_version_validity(conn, "s2", _day("2024-06-01"), _day("2025-02-01"))
    tgsis.set_version_validity(conn, "s3", _day("2025-02-01"))
    return conn


def test_the_version_believed_at_a_date(surveys: Conn) -> None:
    assert [name for name, _, _ in tgsis.version_chain(surveys)] == ["s1", "s2", "s3"]
    assert tgsis.version_believed_at(surveys, _day("2023-12-31")) is None
    assert tgsis.version_believed_at(surveys, _day("2024-01-01")) == "s1"
    assert tgsis.version_believed_at(surveys, _day("2024-05-31")) == "s1"
    assert tgsis.version_believed_at(surveys, _day("2024-06-01")) == "s2"  # [from, to): the next one
    assert tgsis.version_believed_at(surveys, _day("2030-01-01")) == "s3"  # still believed
    assert tgsis.version_chain(surveys, "s2")[0][0] == "s2"


def test_a_chain_must_be_a_line_without_overlaps(surveys: Conn) -> None:
    tgsis.set_version_validity(surveys, "scratch", _day("2024-07-01"), _day("2024-08-01"))  # a sibling of s2
    with pytest.raises(tgsis.InvalidInputError, match="not on one line of descent"):
        tgsis.version_chain(surveys)
    surveys.rollback()
    tgsis.set_version_validity(surveys, "scratch", None)
    tgsis.set_version_validity(surveys, "s2", _day("2024-05-01"), _day("2025-02-01"))
    with pytest.raises(tgsis.InvalidInputError, match="validity periods of versions s1 and s2 overlap"):
        tgsis.version_believed_at(surveys, _day("2024-05-15"))


def test_empty_periods_are_refused(surveys: Conn) -> None:
    with pytest.raises(tgsis.InvalidInputError, match="is empty"):
        tgsis.set_version_validity(surveys, "s1", _day("2024-06-01"), _day("2024-01-01"))
    surveys.rollback()
    with pytest.raises(tgsis.NotFoundError, match="version 'nope' does not exist"):
        tgsis.set_version_validity(surveys, "nope", _day("2024-01-01"))
    surveys.rollback()
    assert surveys.execute("SELECT valid_from::date::text FROM tgsis.versions WHERE name = 's1'").fetchone() == (
        "2024-01-01",
    )


def test_from_the_command_line(db_dsn: str, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["--dsn", db_dsn, "version", "create", "s1"]) == 0
    assert main(["--dsn", db_dsn, "version", "valid", "s1", "2024-01-01"]) == 0
    capsys.readouterr()
    assert main(["--dsn", db_dsn, "version", "chain", "--at", "2024-02-01"]) == 0
    assert capsys.readouterr().out == "s1\n"
    assert main(["--dsn", db_dsn, "version", "chain", "--at", "2023-02-01"]) == 3
    assert main(["--dsn", db_dsn, "version", "chain"]) == 0
    assert capsys.readouterr().out.startswith(
        "-\nversion\tbelieved from\tbelieved to\ns1\t2024-01-01 00:00:00+00:00\tstill believed"
    )
    assert main(["--dsn", db_dsn, "version", "valid", "s1", "yesterday"]) == 1
    assert "is not a date or time" in capsys.readouterr().err
