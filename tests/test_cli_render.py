"""The CLI's renderers alone (issue 38, point 2): a handler computes a result, a renderer prints it.

`render(args, result, text, document)` prints the text for people or, with --json, the one JSON document;
each renderer reads nothing but its result. These tests give renderers results built by hand, with no
database: the cases the command tests reach only with much set-up (a revision that compress removed, a role
that may not read what a solution discards, a G-map feature that does not exist at a time, a local server
that is not running).
"""

from __future__ import annotations

import argparse
import datetime
import json
from typing import Any

import numpy as np
import pytest

from tgsis.cli._output import render
from tgsis.cli._render import summarize_differences
from tgsis.cli.commands import gmaps, local, versions
from tgsis.db import versions as V


def _args(**flags: Any) -> argparse.Namespace:
    return argparse.Namespace(**{"json": False, "no_header": False, **flags})


def test_render_prints_the_text_or_the_json_document_never_both(capsys: pytest.CaptureFixture[str]) -> None:
    said: list[str] = []

    def text(args: argparse.Namespace, result: dict[str, float]) -> None:
        said.append("text")
        print(f"x is {result['x']}")

    def document(result: dict[str, float]) -> dict[str, Any]:
        said.append("document")
        return {"x": result["x"], "when": datetime.datetime(2026, 3, 1, tzinfo=datetime.timezone.utc)}

    assert render(_args(), {"x": float("nan")}, text, document) == 0
    assert capsys.readouterr().out == "x is nan\n" and said == ["text"]
    assert render(_args(json=True), {"x": float("inf")}, text, document) == 0
    assert json.loads(capsys.readouterr().out) == {"x": "Infinity", "when": "2026-03-01T00:00:00+00:00"}
    assert said == ["text", "document"]


def _diff() -> versions.VersionDiff:
    differences = [
        V.Difference("feature", "10", "geometry", 0, 1, 0),
        V.Difference("feature", "10", "vrtx", 0, 3, 0),
        V.Difference("feature", "2", "vrtx", 0, 0, 1),
        V.Difference("well", "w-1", "wells", 1, 0, 0),
    ]
    objects = summarize_differences(differences, "DEFAULT", "edit@3")
    return versions.VersionDiff("DEFAULT", "edit@3", differences, objects)


def test_diff_text_says_per_object_what_differs(capsys: pytest.CaptureFixture[str]) -> None:
    versions.diff_text(_args(), _diff())
    out, err = capsys.readouterr()
    assert out.splitlines() == [
        "class\tkey\tdifference\ttables\tadded\tremoved\tchanged",
        "feature\t10\tonly in DEFAULT\tgeometry,vrtx\t+0\t-4\t~0",
        "feature\t2\tchanged\tvrtx\t+0\t-0\t~1",
        "well\tw-1\tonly in edit@3\twells\t+1\t-0\t~0",
    ]
    assert err == "3 objects differ: 1 only in DEFAULT, 1 only in edit@3, 1 changed\n"
    per_table = versions.VersionDiff(**{**_diff().__dict__, "per_table": True})
    versions.diff_text(_args(no_header=True), per_table)
    out, err = capsys.readouterr()
    assert out.splitlines()[0] == "feature\t10\tgeometry\t+0\t-1\t~0" and len(out.splitlines()) == 4 and err == ""
    versions.diff_text(_args(), versions.VersionDiff("a", "b", [], []))
    assert capsys.readouterr() == ("", "a and b hold the same rows\n")


def test_diff_json_has_both_views() -> None:
    doc = versions.diff_json(_diff())
    assert (doc["a"], doc["b"]) == ("DEFAULT", "edit@3")
    assert [o["objectkey"] for o in doc["objects"]] == ["10", "2", "w-1"]  # the result's order: the handler sorts
    assert doc["objects"][0]["tables"] == ["geometry", "vrtx"] and doc["objects"][0]["removed"] == 4
    assert len(doc["differences"]) == 4 and doc["differences"][3] == {
        "objectclass": "well",
        "objectkey": "w-1",
        "table": "wells",
        "added": 1,
        "removed": 0,
        "changed": 0,
    }


def test_conflicts_text_says_what_this_role_may_not_read(capsys: pytest.CaptureFixture[str]) -> None:
    conflict = V.Conflict("feature", "7", ("vrtx",), ("vrtx", "trgl"), ("vrtx",), "unsolved")
    hidden = versions.VersionConflicts("edit", [conflict], False, {}, None)
    versions.conflicts_text(_args(), hidden)
    out, _ = capsys.readouterr()
    assert out.splitlines()[1] == "feature\t7\tunsolved\tvrtx\tvrtx, trgl\tvrtx\t?\t?"
    assert versions.conflicts_json(hidden)["conflicts"][0]["discards"] is None
    versions.conflicts_text(_args(), versions.VersionConflicts("edit", [], False, {}, {}))
    assert capsys.readouterr() == ("", "version edit has no conflicts with its parent\n")


def test_compression_says_a_remembered_revision_is_gone(capsys: pytest.CaptureFixture[str]) -> None:
    report = [V.Compressed("rows", "tgsis.vrtx_ver", 12), V.Compressed("revisions", "edit", 2)]
    result = versions.Compression(False, report, "edit@4", 4)
    versions.compression_text(_args(), result)
    out, _ = capsys.readouterr()
    assert out.splitlines()[-2:] == [
        "compress removed 12 row version(s), 0 lastrevs entr(ies), 2 revision(s), 0 revision set entr(ies)",
        "revision 4 is gone: commands on this database work in DEFAULT again (was edit@4)",
    ]
    doc = versions.compression_json(result)
    assert doc["forgotten"] == "edit@4" and doc["totals"] == {
        "rows": 12,
        "lastrevs": 0,
        "revisions": 2,
        "set entries": 0,
    }
    versions.compression_text(_args(), versions.Compression(True, [], None, None))
    assert capsys.readouterr().out == "compress would remove nothing (dry run)\n"


def test_gmap_cells_of_a_feature_absent_at_a_time(capsys: pytest.CaptureFixture[str]) -> None:
    absent = gmaps.GMapCells(5, 2, -1.5, 0, np.zeros(0, dtype=np.int64))
    gmaps.gmap_cells_text(_args(), absent)
    assert capsys.readouterr() == ("", "feature 5 does not exist at t = -1.5\n")
    assert gmaps.gmap_cells_json(absent)["darts_per_cell"] == {"min": None, "max": None}
    present = gmaps.GMapCells(5, 2, None, 12, np.array([6, 3, 3]))
    gmaps.gmap_cells_text(_args(), present)
    assert capsys.readouterr().out == "feature 5: 3 2-cells of 12 darts (3..6 darts each)\n"


def test_local_status_of_a_server_not_running(capsys: pytest.CaptureFixture[str]) -> None:
    stopped = local.LocalStatus("/srv/pg", "PostgreSQL 18", False, True, None, None, "host=/run port=5433")
    local.local_status_text(_args(), stopped)
    assert capsys.readouterr().out.splitlines()[-1] == "status:   stopped"
    assert local.local_status_json(stopped)["status"] == "stopped" and local.local_status_json(stopped)["pid"] is None
    running = local.LocalStatus("/srv/pg", "PostgreSQL 18", True, True, 42, None, "host=/run port=5433")
    assert local.local_status_json(running)["started_by"] == "outside tgsis"
