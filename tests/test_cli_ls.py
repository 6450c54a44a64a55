"""`tgsis ls` (issue 38, point 2): filters by name, box and feature property, and shows feature properties.

The filters are those of the browser view's lists (tgsis.db.inspect.list_features, one query for both):
a part of the name in any case; a box meeting the features' bounding boxes; a feature property equal to a
value read as the property's type.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import psycopg
import pytest

import tgsis
from tgsis.cli import main

FLAGGED = Path(__file__).parent / "data" / "gocad" / "flagged.ts"  # F1 (z = 0) and F2 (z = 10)


@pytest.fixture
def data(
    db_dsn: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> dict[str, Any]:
    """Three faults with a text and a number property; a class without feature properties."""
    monkeypatch.setenv("TGSIS_HOME", str(tmp_path / "home"))
    f1, f2 = tgsis.formats.read(FLAGGED)
    far = f1.copy()
    far.vertices = far.vertices + [1000.0, 0.0, 0.0]
    far.name = "Garlock north"
    with psycopg.connect(db_dsn) as conn:
        tgsis.create_feature_class(
            conn, "faults", "SURFACE", feature_properties={"release": "text", "slip": "double precision"}
        )
        ids = [
            tgsis.insert_feature(conn, "faults", m, props)
            for m, props in list[tuple[tgsis.Mesh, dict[str, Any]]](
                [
                    (f1, {"release": "5.3", "slip": 1.5}),
                    (f2, {"release": "6.1", "slip": 2.0}),
                    (far, {"release": "6.1", "slip": None}),
                ]
            )
        ]
        tgsis.create_feature_class(conn, "plain", "SURFACE")
        plain = tgsis.insert_feature(conn, "plain", f1)
    capsys.readouterr()
    return {"dsn": db_dsn, "ids": ids, "plain": plain}


def ls(data: dict[str, Any], capsys: pytest.CaptureFixture[str], *argv: str, code: int = 0) -> str:
    done = main(["--dsn", data["dsn"], "ls", *argv])
    out, err = capsys.readouterr()
    assert done == code, err
    return out if code == 0 else err


def ids_of(out: str) -> list[int]:
    return [f["id"] for f in json.loads(out)["features"]]


def test_ls_shows_feature_properties(data: dict[str, Any], capsys: pytest.CaptureFixture[str]) -> None:
    features = json.loads(ls(data, capsys, "--json"))["features"]
    assert [f["properties"] for f in features] == [
        {"release": "5.3", "slip": 1.5},
        {"release": "6.1", "slip": 2.0},
        {"release": "6.1", "slip": None},
        {},
    ]
    header, *rows = (line.split("\t") for line in ls(data, capsys).splitlines())
    assert header[-1] == "properties" and all(len(r) == len(header) for r in rows)
    assert [r[-1] for r in rows] == ["release=5.3 slip=1.5", "release=6.1 slip=2.0", "release=6.1 slip=", ""]


def test_ls_filters_by_name_box_and_property(data: dict[str, Any], capsys: pytest.CaptureFixture[str]) -> None:
    f1, f2, far = data["ids"]
    assert ids_of(ls(data, capsys, "--json", "--name", "garlock")) == [far]  # a part, in any case
    assert ids_of(ls(data, capsys, "--json", "--name", "F")) == [f1, f2, data["plain"]]
    assert ids_of(ls(data, capsys, "--json", "--box=-1,-1,-1,3,2,1")) == [f1, data["plain"]]
    assert ids_of(ls(data, capsys, "--json", "--box", "999,-1,-1,1003,2,1")) == [far]
    assert ids_of(ls(data, capsys, "--json", "--class", "faults", "--property", "release=6.1")) == [f2, far]
    # the value is read as the property's type: 2 equals 2.0
    assert ids_of(ls(data, capsys, "--json", "--class", "faults", "--property", "slip=2")) == [f2]
    assert ids_of(
        ls(
            data,
            capsys,
            "--json",
            "--class",
            "faults",
            "--property",
            "release=6.1",
            "--property",
            "slip=2",
            "--name",
            "f2",
        )
    ) == [f2]
    assert main(["--dsn", data["dsn"], "ls", "--name", "nothing like it"]) == 0
    assert capsys.readouterr() == ("", "no features\n")


def test_ls_refuses_bad_filters(data: dict[str, Any], capsys: pytest.CaptureFixture[str]) -> None:
    err = ls(data, capsys, "--property", "release=6.1", code=1)
    assert "--class" in err  # a property belongs to a class
    err = ls(data, capsys, "--class", "faults", "--property", "nope=1", code=1)
    assert "no feature property 'nope'" in err and "release, slip" in err
    err = ls(data, capsys, "--class", "faults", "--property", "slip=fast", code=1)
    assert "fast" in err
    err = ls(data, capsys, "--class", "faults", "--property", "release", code=1)
    assert "NAME=VALUE" in err
    with pytest.raises(SystemExit):
        main(["--dsn", data["dsn"], "ls", "--box", "1,2,3"])
    with pytest.raises(SystemExit):
        main(["--dsn", data["dsn"], "ls", "--box", "3,0,0,1,1,1"])  # min > max
