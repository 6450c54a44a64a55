"""`--json` and header lines of every command that lists or reports, against a real database.

Each command runs twice on the same data: with ``--json`` (its stdout parsed as
one JSON document, the keys docs/cli.md names checked), and as tab-separated
lines (the header line names the columns, every row has as many).
"""

from __future__ import annotations

import datetime
import json
from pathlib import Path
from typing import Any

import numpy as np
import psycopg
import pytest

import tgsis
from tests.temporal_data import evolving
from tgsis.cli import main

FLAGGED = Path(__file__).parent / "data" / "gocad" / "flagged.ts"  # surfaces F1 and F2


@pytest.fixture
def data(
    db_dsn: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> dict[str, Any]:
    """Two static faults in DEFAULT, edited on both sides of a version `a` (a conflict), a model-3 fault."""
    monkeypatch.setenv("TGSIS_HOME", str(tmp_path / "home"))
    moving = evolving(np.random.default_rng(5), [-10.0, -6.5], instants_per_period=3, with_properties=True)
    with psycopg.connect(db_dsn) as conn:
        tgsis.create_feature_class(conn, "faults", "SURFACE", feature_properties={"release": "text"})
        ids = [tgsis.insert_feature(conn, "faults", m, {"release": "5.3"}) for m in tgsis.formats.read(FLAGGED)]
        classes = tgsis.create_feature_class(
            conn,
            "moving",
            "SURFACE",
            time_model="EVOLVING",
            time_unit="Ma",
            cell_properties=[("porosity", "double precision")],
            instant_properties=[("throw", "double precision"), ("note_code", "integer")],
        )
        mid = tgsis.insert_feature(conn, classes, moving)
        tgsis.enable_feature_versioning(conn)
        tgsis.create_version(conn, "a")
        conn.execute("UPDATE tgsis.vrtx SET z = z + 1 WHERE geoid = %s AND vrtxid = 1", (ids[0],))
        with tgsis.in_version(conn, "a"):
            conn.execute("UPDATE tgsis.vrtx SET z = z - 1 WHERE geoid = %s AND vrtxid = 1", (ids[0],))
        conn.commit()
        tgsis.lock_objects(conn, "a", "feature", [str(ids[1])])
        tgsis.grant_version(conn, "a", "write", "tgsis_editor")
        tgsis.set_version_validity(
            conn, "a", datetime.datetime(2024, 1, 1, 12, 0, 0, 123456, tzinfo=datetime.timezone.utc), None
        )
    capsys.readouterr()
    return {"dsn": db_dsn, "ids": ids, "moving": mid, "tmp": tmp_path}


def run(data: dict[str, Any], capsys: pytest.CaptureFixture[str], *argv: str) -> str:
    code = main(["--dsn", data["dsn"], *argv])
    out, err = capsys.readouterr()
    assert code == 0, err
    return out


def as_json(data: dict[str, Any], capsys: pytest.CaptureFixture[str], *argv: str) -> Any:
    out = run(data, capsys, *argv, "--json")
    assert out.count("\n") == 1, out  # one document, one line
    return json.loads(out, parse_constant=lambda name: pytest.fail(f"not strict JSON: {name}"))


def table(
    data: dict[str, Any], capsys: pytest.CaptureFixture[str], *argv: str, again: bool = True
) -> tuple[list[str], list[list[str]]]:
    """The header and rows of a command's tab-separated output; ``again``: also run it with --no-header."""
    lines = run(data, capsys, *argv).splitlines()
    header = lines[0].split("\t")
    rows = [line.split("\t") for line in lines[1:] if not line.startswith("wrote ")]  # series' closing line
    assert all(len(row) == len(header) for row in rows), (header, rows)
    if again:
        bare = run(data, capsys, *argv, "--no-header").splitlines()
        assert bare == lines[1:]
    return header, rows


def test_ls(data: dict[str, Any], capsys: pytest.CaptureFixture[str]) -> None:
    doc = as_json(data, capsys, "ls")
    assert [f["id"] for f in doc["features"]] == [*data["ids"], data["moving"]]
    assert doc["features"][0] == {
        "id": data["ids"][0],
        "class": "faults",
        "name": "F1",
        "geotype": "SURFACE",
        "vertices": 6,
        "cells": 4,
        "members": None,
        "darts": None,
        "properties": {"release": "5.3"},
    }
    header, rows = table(data, capsys, "ls")
    assert header == ["id", "class", "name", "geotype", "vertices", "cells", "members", "darts", "properties"]
    assert rows[0] == [str(data["ids"][0]), "faults", "F1", "SURFACE", "6", "4", "", "", "release=5.3"]


def test_class_list(data: dict[str, Any], capsys: pytest.CaptureFixture[str]) -> None:
    doc = as_json(data, capsys, "class", "list")
    moving = next(c for c in doc["classes"] if c["name"] == "moving")
    assert moving["time_model"] == "EVOLVING" and moving["time_unit"] == "Ma"
    assert moving["instant_properties"] == [
        {"name": "throw", "type": "double precision"},
        {"name": "note_code", "type": "integer"},
    ]
    assert moving["properties"] == [{"name": "porosity", "type": "double precision", "size": 1, "alignment": "VERTEX"}]
    header, rows = table(data, capsys, "class", "list")
    assert header[:4] == ["class", "geotype", "srs", "schema"] and [r[0] for r in rows] == ["faults", "moving"]


def test_version_list_tree_current(data: dict[str, Any], capsys: pytest.CaptureFixture[str]) -> None:
    doc = as_json(data, capsys, "version", "list")
    assert doc["current"] == "DEFAULT" and [v["name"] for v in doc["versions"]] == ["DEFAULT", "a"]
    a = doc["versions"][1]
    assert (
        {
            "parent",
            "initrevision",
            "working_revision",
            "revisions",
            "saved",
            "owner",
            "created_at",
            "description",
            "current",
        }
        <= set(a)
        and a["parent"] == "DEFAULT"
        and a["current"] is False
    )
    assert "." in a["created_at"] or "+" in a["created_at"]  # ISO 8601, exact
    header, rows = table(data, capsys, "version", "list")
    assert header == ["current", "version", "parent", "initrevision", "working", "owner", "created", "description"]
    assert rows[0][:2] == ["*", "DEFAULT"] and "." not in rows[1][6]  # to the second for people
    tree = as_json(data, capsys, "version", "tree")
    assert [(v["name"], v["depth"]) for v in tree["versions"]] == [("DEFAULT", 0), ("a", 1)]
    assert as_json(data, capsys, "--in", "a", "version", "current") == {
        "version": "a",
        "working_revision": a["working_revision"],
        "viewing_revision": None,
        "read_only": False,
        "source": "--in",
    }


def test_version_conflicts_and_diff(data: dict[str, Any], capsys: pytest.CaptureFixture[str]) -> None:
    fid = str(data["ids"][0])
    doc = as_json(data, capsys, "version", "conflicts", "a", "--rows")
    assert doc["version"] == "a" and [c["objectkey"] for c in doc["conflicts"]] == [fid]
    conflict = doc["conflicts"][0]
    assert conflict["solution"] == "unsolved" and "vrtx" in conflict["both_changed"]
    assert {r["side"] for r in conflict["rows"]} == {"child", "parent"}
    assert "rows" not in as_json(data, capsys, "version", "conflicts", "a")["conflicts"][0]
    header, rows = table(data, capsys, "version", "conflicts", "a")
    assert header[:3] == ["class", "key", "solution"] and rows[0][:3] == ["feature", fid, "unsolved"]
    diff = as_json(data, capsys, "version", "diff", "DEFAULT", "a")
    assert (
        diff["a"] == "DEFAULT"
        and {"objectclass": "feature", "objectkey": fid, "table": "vrtx", "added": 0, "removed": 0, "changed": 1}
        in diff["differences"]
    )
    assert {
        "objectclass": "feature",
        "objectkey": fid,
        "difference": "changed",
        "tables": ["vrtx"],
        "added": 0,
        "removed": 0,
        "changed": 1,
    } in diff["objects"]
    header, rows = table(data, capsys, "version", "diff", "DEFAULT", "a")
    assert header == ["class", "key", "difference", "tables", "added", "removed", "changed"]
    assert ["feature", fid, "changed", "vrtx", "+0", "-0", "~1"] in rows
    header, rows = table(data, capsys, "version", "diff", "DEFAULT", "a", "--tables")
    assert (
        header == ["class", "key", "table", "added", "removed", "changed"]
        and ["feature", fid, "vrtx", "+0", "-0", "~1"] in rows
    )


def test_locks_privileges_chain_versioning_compress(data: dict[str, Any], capsys: pytest.CaptureFixture[str]) -> None:
    locks = as_json(data, capsys, "version", "locks")["locks"]
    assert [(lk["objectkey"], lk["version"], lk["exclusive"]) for lk in locks] == [(str(data["ids"][1]), "a", False)]
    assert table(data, capsys, "version", "locks")[0] == ["class", "key", "version", "role", "kind", "since"]
    grants = as_json(data, capsys, "version", "privileges", "a")["versions"][0]
    assert (
        grants["name"] == "a" and {"role": "tgsis_editor", "privilege": "write"}.items() <= grants["grants"][0].items()
    )
    chain = as_json(data, capsys, "version", "chain")["chain"]
    assert chain[-1]["version"] == "a" and chain[-1]["valid_from"] == "2024-01-01T12:00:00.123456+00:00"
    header, rows = table(data, capsys, "version", "chain")
    assert header == ["version", "believed from", "believed to"] and rows[-1][1] == "2024-01-01 12:00:00+00:00"
    tables = as_json(data, capsys, "versioning", "list")["tables"]
    assert {"schema": "tgsis", "table": "vrtx"}.items() <= next(t for t in tables if t["table"] == "vrtx").items()
    assert table(data, capsys, "versioning", "list")[0][:3] == ["table", "class", "key"]
    compress = as_json(data, capsys, "version", "compress", "--dry-run")
    assert compress["dry_run"] is True and set(compress["totals"]) == {"rows", "lastrevs", "revisions", "set entries"}


def test_info_query_series(data: dict[str, Any], capsys: pytest.CaptureFixture[str]) -> None:
    mid = data["moving"]
    info = as_json(data, capsys, "info", str(mid))
    assert info["id"] == mid and info["class"] == "moving" and info["time_model"] == "EVOLVING"
    assert info["lifespan"] == {"first": -10.0, "last": info["instants"][-1]["t"], "alive": False}
    assert [i["t"] for i in info["instants"] if i["topology"]] == [-10.0, -6.5]
    assert set(info["box"]) == {"x", "y", "z"} and info["versioned"] is True
    static = as_json(data, capsys, "info", str(data["ids"][0]))
    assert static["lifespan"] is None and [d["version"] for d in static["differs_in"]] == ["a"]
    query = as_json(data, capsys, "query", "moving", "throw", "<", "inf")
    assert [f["id"] for f in query["features"]] == [mid]
    period = query["features"][0]["periods"][0]
    assert set(period) == {"start", "end", "start_closed", "end_closed"} and period["start"] == -10.0
    assert query["value"] == "Infinity"  # strict JSON: non-finite numbers as strings
    assert table(data, capsys, "query", "moving", "throw", "<", "inf")[0] == ["id", "periods"]
    assert table(data, capsys, "query", "moving", "throw", "<", "inf", "--first")[0] == ["id", "first", "when"]
    out = data["tmp"] / "series"
    series = as_json(data, capsys, "series", str(mid), str(out), "--from", "-10", "--to", "-8", "--steps", "11")
    assert series["pvd"] == str(out / f"feature_{mid}.pvd") and len(series["frames"]) == 11
    assert series["frames"][9]["t"] == np.linspace(-10, -8, 11)[9]  # exact: -8.200000000000001 or so
    header, rows = table(data, capsys, "series", str(mid), str(out), "--from", "-10", "--to", "-8", "--steps", "11")
    assert header == ["t", "file", "vertices", "triangles"] and len(rows) == 11
    assert [r[0] for r in rows[:11]] == [
        "-10.0",
        "-9.8",
        "-9.6",
        "-9.4",
        "-9.2",
        "-9.0",
        "-8.8",
        "-8.6",
        "-8.4",
        "-8.2",
        "-8.0",
    ]  # rounded for people


def test_db_status(data: dict[str, Any], capsys: pytest.CaptureFixture[str]) -> None:
    doc = as_json(data, capsys, "db", "status")
    assert doc["tgsis"] == tgsis.__version__ and doc["client"] == tgsis.__version__ and "PostgreSQL" in doc["server"]


def test_import_and_checkin(data: dict[str, Any], capsys: pytest.CaptureFixture[str]) -> None:
    doc = as_json(data, capsys, "--in", "a", "import", str(FLAGGED), "--class", "faults")
    assert [(f["name"], f["replaced"], f["same_name"]) for f in doc["features"]] == [
        ("F1", None, [data["ids"][0]]),
        ("F2", None, [data["ids"][1]]),
    ]
    assert doc["features"][0]["defects"] == {
        "duplicate_vertices": 1,
        "degenerate_cells": 1,
        "summary": "1 duplicate vertices, 1 degenerate cells",
    }
    header, rows = table(data, capsys, "--in", "a", "import", str(FLAGGED), "--class", "faults", again=False)
    assert header == ["id", "name", "geotype", "vertices", "cells", "replaced", "defects"]
    assert [r[1] for r in rows] == ["F1", "F2"]
    path = data["tmp"] / "f.ts"
    fid = data["ids"][0]  # (the other one is locked by version a)
    run(data, capsys, "checkout", str(fid), str(path))
    mesh = tgsis.formats.read_one(path)
    mesh.vertices[0, 2] += 1.0
    tgsis.formats.write(mesh, path)
    doc = as_json(data, capsys, "checkin", str(path))
    assert doc["feature_id"] == fid and doc["version"] == "DEFAULT" and doc["conflict"] is False
    assert doc["vertices"] == {"kept": mesh.n_vertices - 1, "moved": 1, "removed": 0, "added": 0}
    assert set(doc["rows"]) == {"written", "deleted", "inserted", "updated"} and doc["commands"] == []
    assert doc["record"] == f"{path}.tgsis-checkout.npz"


@pytest.mark.own_server  # a server of TGSIS_PG's binaries, not the fixture pg's
def test_local_status(tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]) -> None:
    monkeypatch.setenv("TGSIS_HOME", str(tmp_path / "home"))
    assert main(["local", "status", "--json"]) == 3
    doc = json.loads(capsys.readouterr().out)
    assert doc["status"] == "not created" and doc["pid"] is None and "dbname=tgsis" in doc["dsn"]
