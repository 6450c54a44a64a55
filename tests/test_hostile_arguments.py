"""Bad arguments at the public entry points give our errors naming the argument, never a raw PostgreSQL one.

Issue 15 found raw 22P02 (invalid text representation), 23514 (check
violation), 42883 (undefined function: an integer too large for the SQL
parameter), psycopg's NUL-byte error with no SQLSTATE and no field, NaN
reaching tgsis.timerange, and a MemoryError traceback from
``tgsis series --steps 100000000000``. Each case here failed before its fix.
"""

from __future__ import annotations

import datetime
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import psycopg
import pytest

import tgsis
from tgsis.cli import main
from tgsis.db import temporal as T
from tgsis.db import versions as V

Conn = psycopg.Connection[Any]


def _surface(z: float = 0.0) -> tgsis.Surface:
    return tgsis.Surface(np.array([[0, 0, z], [1, 0, z], [0, 1, z]], dtype=float), np.array([[0, 1, 2]]))


def _state(conn: Conn) -> list[Any]:
    """What the refused calls could have changed."""
    return [
        conn.execute(q).fetchall()
        for q in (
            "SELECT * FROM tgsis.catalog ORDER BY 1",
            "SELECT geoid, geoname FROM tgsis.geometry ORDER BY 1",
            "SELECT name FROM tgsis.versions ORDER BY 1",
            "SELECT schemaname, tablename FROM tgsis.versioned_tables ORDER BY 1",
            "SELECT count(*) FROM tgsis.vrtx",
        )
    ]


def _period() -> tgsis.TopologyPeriod:
    surface = _surface()
    return tgsis.TopologyPeriod(np.array([0.0, 1.0]), surface.triangles, np.stack([surface.vertices, surface.vertices]))


@pytest.fixture
def db(conn: Conn) -> Conn:
    tgsis.create_feature_class(conn, "faults", "SURFACE", feature_properties={"release": "text"})
    tgsis.create_feature_class(conn, "moving", "SURFACE", time_model="EVOLVING", time_unit="Ma")
    tgsis.insert_feature(conn, "faults", _surface())
    conn.commit()
    return conn


NUL = "a\x00b"

# (label, call, message fragment naming the argument)
PYTHON_CASES: list[tuple[str, Callable[[Conn], Any], str]] = [
    ("class name", lambda c: tgsis.create_feature_class(c, NUL, "SURFACE"), "name contains a NUL byte"),
    (
        "property name",
        lambda c: tgsis.create_feature_class(c, "x", "SURFACE", feature_properties={NUL: "text"}),
        "a key of feature_properties contains a NUL byte",
    ),
    (
        "description",
        lambda c: tgsis.create_feature_class(c, "x", "SURFACE", description=NUL),
        "description contains a NUL byte",
    ),
    (
        "time unit",
        lambda c: tgsis.create_feature_class(c, "x", "SURFACE", time_model="EVOLVING", time_unit=NUL),
        "time_unit contains a NUL byte",
    ),
    ("srs text", lambda c: tgsis.create_feature_class(c, "x", "SURFACE", srs="abc"), "srs must be an integer"),  # type: ignore[arg-type]
    (
        "srs huge",
        lambda c: tgsis.create_feature_class(c, "x", "SURFACE", srs=10**12),
        "srs = 1000000000000 is out of range",
    ),
    ("class lookup", lambda c: tgsis.get_feature_class(c, NUL), "name contains a NUL byte"),
    ("feature name", lambda c: tgsis.insert_feature(c, "faults", _surface(), name=NUL), "name contains a NUL byte"),
    (
        "feature property",
        lambda c: tgsis.insert_feature(c, "faults", _surface(), {"release": NUL}),
        "properties['release'] contains a NUL byte",
    ),
    ("feature id text", lambda c: tgsis.fetch_feature(c, "faults", "abc"), "feature_id must be an integer"),  # type: ignore[arg-type]
    (
        "feature id huge",
        lambda c: tgsis.delete_feature(c, "faults", 10**20),
        "feature_id = 100000000000000000000 is out of range",
    ),
    ("version name", lambda c: V.create_version(c, NUL), "name contains a NUL byte"),
    ("version name type", lambda c: V.create_version(c, 5), "name must be a string, not int 5"),  # type: ignore[arg-type]
    ("goto", lambda c: V.goto_version(c, NUL), "name contains a NUL byte"),
    ("revision text", lambda c: V.goto_revision(c, "DEFAULT", "abc"), "revision must be an integer"),  # type: ignore[arg-type]
    ("revision huge", lambda c: V.goto_revision(c, "DEFAULT", 10**12), "revision = 1000000000000 is out of range"),
    ("grant role", lambda c: V.grant_version(c, "DEFAULT", "write", NUL), "role contains a NUL byte"),
    ("lock key", lambda c: V.lock_objects(c, "DEFAULT", "feature", [NUL]), "keys[0] contains a NUL byte"),
    (
        "believed root",
        lambda c: V.version_believed_at(c, datetime.datetime.now(datetime.timezone.utc), NUL),
        "root contains a NUL byte",
    ),
    ("versioning table", lambda c: V.enable_versioning(c, NUL, "id", "c"), "table contains a NUL byte"),
    ("iudorder huge", lambda c: V.enable_versioning(c, "faults", "_geoid", "c", 10**12), "iudorder = 1000000000000"),
    (
        "diff revision",
        lambda c: V.diff_versions(c, "DEFAULT", "DEFAULT", a_revision=10**12),
        "a_revision = 1000000000000",
    ),
    ("time text", lambda c: tgsis.get_at(c, 1, "abc"), "t must be a number, not str"),  # type: ignore[arg-type]
    ("time id huge", lambda c: tgsis.get_at(c, 10**20, 1.0), "feature_id = 100000000000000000000"),
    ("question property", lambda c: T.property_periods(c, "moving", 1, NUL, "<", 1.0), "prop contains a NUL byte"),
    ("snapshot class", lambda c: T.surfaces_at(c, NUL, 1.0), "feature_class contains a NUL byte"),
    # these three were not in their module's __all__, so the module-end wrapping missed them (issue 38)
    (
        "append period id huge",
        lambda c: T.append_period(c, "moving", 10**20, _period()),
        "feature_id = 100000000000000000000 is out of range",
    ),
    ("delete period id huge", lambda c: T.delete_period(c, 10**20, 0.0), "feature_id = 100000000000000000000"),
    ("delete period start text", lambda c: T.delete_period(c, 1, "abc"), "start must be a number, not str"),  # type: ignore[arg-type]
    (
        "class question property",
        lambda c: T.class_property_periods(c, "moving", NUL, "<", 1.0),
        "prop contains a NUL byte",
    ),
    (
        "class question value text",
        lambda c: T.class_property_periods(c, "moving", "p", "<", "abc"),  # type: ignore[arg-type]
        "value must be a number, not str",
    ),
    (
        "steps",
        lambda c: T.export_series(c, 1, "/nonexistent/s.pvd", start=0.0, end=1.0, steps=10**11),
        "steps 100000000000 is too many: at most 100000",
    ),
]


@pytest.mark.parametrize("case", PYTHON_CASES, ids=[case[0] for case in PYTHON_CASES])
def test_python_arguments(db: Conn, case: tuple[str, Callable[[Conn], Any], str]) -> None:
    _, call, message = case
    before = _state(db)
    with pytest.raises(tgsis.InvalidInputError, match=message.replace("[", r"\[").replace("]", r"\]")) as caught:
        call(db)
    assert caught.value.sqlstate == "TG100"
    assert not isinstance(caught.value, tgsis.DatabaseError)
    db.rollback()
    assert _state(db) == before


# (label, SQL, SQLSTATE, message fragment); the database is checked unchanged after each
SQL_CASES = [
    (
        "unknown geotype",
        "SELECT tgsis.new_geometry('CUBE', 'x', NULL, 0, 0)",
        "TG102",
        "geotype 'CUBE' of a new geometry is unknown",
    ),
    ("negative counts", "SELECT tgsis.new_geometry('SURFACE', 'x', NULL, -1, 0)", "TG102", "p_nvrtx => -1"),
    (
        "three-part table name",
        "SELECT tgsis.enable_versioning('a.b.c', 'id', 'c')",
        "TG200",
        "table 'a.b.c' does not exist",
    ),
    (
        "NaN end of a linear period",
        "SELECT tgsis.linear_satisfied(0, 'NaN', 1, 2, '<', 1.5)",
        "TG100",
        "p_t0, p_t1 = 0 and NaN are no period",
    ),
    (
        "reversed linear period",
        "SELECT tgsis.linear_satisfied(2, 1, 1, 2, '<', 1.5)",
        "TG100",
        "p_t0, p_t1 = 2 and 1 are no period",
    ),
    (
        "NaN topology period",
        "SELECT tgsis.evolving_satisfied(0, 'NaN', 0, 1, 1, 2, false, '<', 1.5)",
        "TG100",
        "p_timem, p_next_timem = 0 and NaN are no period",
    ),
    # a period made by hand: tgsis.timerange refuses NaN bounds by name (PostgreSQL's range type took
    # '[1,NaN)' as everything from 1 on, and refused ('NaN', 1) with a raw 22000 about bound order)
    ("NaN lower bound of a period", "SELECT tgsis.timerange('NaN', 1)", "TG100", "NaN is no bound of a period"),
    ("NaN upper bound of a period", "SELECT tgsis.timerange(1, 'NaN', '[]')", "TG100", "NaN is no bound of a period"),
    ("NaN bound of a period literal", "SELECT '[1,NaN)'::tgsis.timerange", "TG100", "NaN is no bound of a period"),
    (
        "NaN bound of a period cast",
        "SELECT tgsis.modeltime_range('-Infinity', 'NaN')::tgsis.timerange",
        "TG100",
        "NaN is no bound of a period",
    ),
    ("reversed period", "SELECT tgsis.timerange(2, 1)", "TG100", "lower bound 2 of a period of model time is after"),
    ("unknown bounds of a period", "SELECT tgsis.timerange(1, 2, '[[')", "TG100", "bounds '[[' of a period"),
]


@pytest.mark.parametrize("case", SQL_CASES, ids=[case[0] for case in SQL_CASES])
def test_sql_arguments(db: Conn, case: tuple[str, str, str, str]) -> None:
    _, query, sqlstate, message = case
    before = _state(db)
    with pytest.raises(psycopg.Error) as caught:
        db.execute(query)
    assert caught.value.sqlstate == sqlstate, caught.value.diag.message_primary
    assert message in (caught.value.diag.message_primary or "")
    assert caught.value.diag.message_hint
    db.rollback()
    assert _state(db) == before


def test_sql_interval_helpers_still_answer_good_periods(db: Conn) -> None:
    assert db.execute("SELECT tgsis.linear_satisfied(0, 1, 1, 2, '<', 1.5)::text").fetchone() == ("{(0,0.5)}",)
    assert db.execute(
        "SELECT tgsis.evolving_satisfied(0, NULL, 0, NULL, 1, NULL, true, '<', 1.5)::text"
    ).fetchone() == ("{[0,)}",)


def test_object_keys_that_are_no_feature_ids(db: Conn) -> None:
    tgsis.enable_feature_versioning(db)
    V.create_version(db, "v1")
    db.commit()
    before = _state(db)
    for keys, shown in ((["abc"], "'abc'"), ([str(10**20)], "'100000000000000000000'")):
        with pytest.raises(
            tgsis.InvalidInputError, match=f"object key {shown} of class 'feature' is not a bigint"
        ) as caught:
            V.lock_objects(db, "v1", "feature", keys)
        assert caught.value.sqlstate == "TG100" and caught.value.hint is not None
        db.rollback()
    assert _state(db) == before
    assert db.execute("SELECT count(*) FROM tgsis.object_locks").fetchone() == (0,)


def _cli(dsn: str, capsys: pytest.CaptureFixture[str], *argv: str) -> tuple[int, str]:
    code = main(["--dsn", dsn, *argv])
    return code, capsys.readouterr().err


def test_cli_series_with_too_many_steps(
    db: Conn, db_dsn: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    fid = tgsis.insert_feature(
        db,
        "moving",
        tgsis.EvolvingSurface(
            [tgsis.TopologyPeriod([-1.0, 0.0], _surface().triangles, [_surface().vertices, _surface(1).vertices])]
        ),
    )
    db.commit()
    code, err = _cli(
        db_dsn, capsys, "series", str(fid), str(tmp_path / "out"), "--from", "0", "--to", "1", "--steps", "200000"
    )
    assert code == 1 and "--steps 200000 is too many: at most 100000" in err and "Traceback" not in err
    assert not (tmp_path / "out").exists()
    with pytest.raises(SystemExit) as usage:  # beyond the SQL integer: a usage error naming the flag
        main(
            [
                "--dsn",
                db_dsn,
                "series",
                str(fid),
                str(tmp_path / "out"),
                "--from",
                "0",
                "--to",
                "1",
                "--steps",
                "100000000000",
            ]
        )
    assert usage.value.code == 2
    assert "argument --steps: 100000000000 is out of range" in capsys.readouterr().err


def test_cli_series_steps_in_the_console_script(db: Conn, db_dsn: str, tmp_path: Path) -> None:
    # the command as a user types it: no traceback, whatever the form of the number
    for steps, code, message in (
        ("1e11", 2, "argument --steps: invalid integer value: '1e11'"),
        ("100000000000", 2, "argument --steps: 100000000000 is out of range"),
    ):
        done = subprocess.run(
            [
                str(Path(sys.executable).parent / "tgsis"),
                "--dsn",
                db_dsn,
                "series",
                "1",
                str(tmp_path / "o"),
                "--from",
                "0",
                "--to",
                "1",
                "--steps",
                steps,
            ],
            capture_output=True,
            text=True,
            timeout=120,
            check=False,
        )
        assert done.returncode == code and message in done.stderr and "Traceback" not in done.stderr


@pytest.mark.parametrize(
    "argv, message",
    [
        (
            ["class", "create", "big", "--geotype", "SURFACE", "--srs", "99999999999"],
            "argument --srs: 99999999999 is out of range",
        ),
        (
            ["versioning", "enable", "faults", "--key", "_geoid", "--class", "c", "--order", "99999999999"],
            "argument --order: 99999999999 is out of range",
        ),
        (["export", "99999999999999999999", "out.ts"], "argument id: 99999999999999999999 is out of range"),
        (["at", "abc", "0", "out.ts"], "argument id: invalid integer value: 'abc'"),
    ],
)
def test_cli_integers_out_of_range_are_usage_errors(
    db: Conn, db_dsn: str, capsys: pytest.CaptureFixture[str], argv: list[str], message: str
) -> None:
    before = _state(db)
    with pytest.raises(SystemExit) as usage:
        main(["--dsn", db_dsn, *argv])
    assert usage.value.code == 2 and message in capsys.readouterr().err
    assert _state(db) == before


@pytest.mark.parametrize(
    "argv, message",
    [
        (["version", "goto", "v1@99999999999"], "revision 99999999999 of 'v1@99999999999' is out of range"),
        (["version", "goto", "v1@²"], "'v1@²' is not VERSION or VERSION@REVISION"),
        (["version", "lock", "v1", "feature", "abc"], "object key 'abc' of class 'feature' is not a bigint"),
    ],
)
def test_cli_bad_values_name_the_argument(
    db: Conn,
    db_dsn: str,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
    argv: list[str],
    message: str,
) -> None:
    monkeypatch.setenv("TGSIS_HOME", str(tmp_path))
    monkeypatch.delenv("TGSIS_VERSION", raising=False)
    tgsis.enable_feature_versioning(db)
    V.create_version(db, "v1")
    db.commit()
    before = _state(db)
    code, err = _cli(db_dsn, capsys, *argv)
    assert code == 1 and message in err and "Traceback" not in err
    assert _state(db) == before


@pytest.mark.parametrize("call", ["read", "write"])
def test_file_names_with_a_nul_byte(call: str) -> None:
    # before: a bare ValueError ("embedded null byte") from open()
    from tgsis import formats

    with pytest.raises(tgsis.FileFormatError, match="the file name contains a NUL byte"):
        if call == "read":
            formats.read("fault\x00.ts")
        else:
            formats.write(_surface(), "fault\x00.ts")
