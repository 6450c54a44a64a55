"""Object keys are the same text whatever the session's settings (issue 36, point 3).

Versioning turns object keys into text (advisory lock keys, tgsis.object_locks,
tgsis.revision_objects, tgsis.conflicts, diffs, merges) and back into the key
column's type. Both directions must not depend on DateStyle, TimeZone,
IntervalStyle, extra_float_digits or bytea_output: two sessions with different
settings working on one object must see one object.
"""

from __future__ import annotations

from typing import Any

import psycopg
import pytest

import tgsis
from tgsis.errors import reraise

Conn = psycopg.Connection[Any]


def _session(dsn: str, **settings: str) -> Conn:
    conn = psycopg.connect(dsn)
    for name, value in settings.items():
        conn.execute("SELECT pg_catalog.set_config(%s, %s, false)", (name, value))
    conn.commit()
    return conn


def _write(conn: Conn, version: str, statement: str, params: Any = None) -> None:
    with reraise(), tgsis.in_version(conn, version, local=True):
        conn.execute(statement, params)
    conn.commit()


def test_a_date_key_edited_under_sql_dmy_is_the_locked_object_and_survives_the_merge(conn: Conn, db_dsn: str) -> None:
    """The issue's report: an edit under DateStyle 'SQL, DMY' wrote through another version's lock, and its merge lost it."""
    conn.execute("CREATE TABLE days (d date PRIMARY KEY, v integer NOT NULL)")
    conn.execute("INSERT INTO days VALUES ('2024-01-02', 1), ('2024-02-01', 2)")
    conn.commit()
    tgsis.enable_versioning(conn, "days", "d", "day")
    tgsis.create_version(conn, "v1")
    tgsis.create_version(conn, "v2")
    tgsis.lock_objects(conn, "v1", "day", ["2024-01-02"])
    dmy = _session(db_dsn, DateStyle="SQL, DMY")
    try:
        with pytest.raises(tgsis.ObjectLockedError, match="2024-01-02"):
            _write(dmy, "v2", "UPDATE days SET v = 10 WHERE d = DATE '2024-01-02'")
        dmy.rollback()
        _write(dmy, "v2", "UPDATE days SET v = 20 WHERE d = DATE '2024-02-01'")
        tgsis.merge_version(dmy, "v2")
    finally:
        dmy.close()
    rows = conn.execute("SELECT d::text, v FROM tgsis.rows_at(NULL::days, 'DEFAULT') ORDER BY d").fetchall()
    conn.rollback()
    assert rows == [("2024-01-02", 1), ("2024-02-01", 20)]
