"""The command line's conflict story through the merge: checkin --on-conflict child, version conflicts/resolve/merge."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import psycopg
import pytest

import tgsis
from tests.test_cli_checkin import _surface
from tgsis import formats
from tgsis.cli import main

ANN, BOB = 1, 2  # the vertex each moves: neighbours, so that the edits meet in one region (a conflict)


@pytest.fixture
def fault(db_dsn: str) -> int:
    with psycopg.connect(db_dsn) as conn:
        tgsis.create_feature_class(conn, "faults", "SURFACE", cell_properties={"porosity": "float8"})
        tgsis.enable_feature_versioning(conn)
        return tgsis.insert_feature(conn, "faults", _surface())


def _edit_file(path: Path, moves: dict[int, float]) -> None:
    """What a desktop tool does: read the file, move vertices (given by their index in _surface()), write it back."""
    mesh = formats.read_one(path)
    base = _surface()
    for i, z in moves.items():
        at = np.flatnonzero((mesh.vertices[:, :2] == base.vertices[i, :2]).all(axis=1))
        assert len(at) == 1
        mesh.vertices[at, 2] = z
    formats.write(mesh, path)


def _z(dsn: str, fid: int, version: str = "DEFAULT") -> tuple[float, float]:
    """Heights of Ann's and Bob's vertices as ``version`` holds the fault."""
    with psycopg.connect(dsn) as conn, tgsis.in_version(conn, version):
        mesh = tgsis.fetch_feature(conn, "faults", fid).mesh
    assert isinstance(mesh, tgsis.Mesh)
    base = _surface()
    z = {(x, y): h for x, y, h in mesh.vertices}
    return z[tuple(base.vertices[ANN, :2])], z[tuple(base.vertices[BOB, :2])]


@pytest.mark.parametrize("solution", ["parent", "child", "manual"])
def test_the_conflict_goes_through_the_merge(
    db_dsn: str, fault: int, tmp_path: Path, solution: str, capsys: pytest.CaptureFixture[str]
) -> None:
    cli = ["--dsn", db_dsn]
    ann, bob = tmp_path / "ann.ts", tmp_path / "bob.vtu"
    assert main([*cli, "checkout", str(fault), str(bob)]) == 0  # Bob first, Ann edits meanwhile
    assert main([*cli, "checkout", str(fault), str(ann)]) == 0
    _edit_file(ann, {ANN: 5.0})
    assert main([*cli, "checkin", str(ann)]) == 0
    _edit_file(bob, {BOB: -5.0})
    capsys.readouterr()
    assert main([*cli, "checkin", str(bob), "--on-conflict", "child", "--child-version", "bob_fix"]) == 0
    out = capsys.readouterr().out
    assert "into version bob_fix (a new child version" in out
    assert "tgsis version conflicts bob_fix" in out and "tgsis version merge bob_fix" in out
    original = _surface().vertices
    assert _z(db_dsn, fault, "bob_fix") == (original[ANN, 2], -5.0)  # Ann's edit is not reverted in the child

    assert main([*cli, "version", "conflicts", "bob_fix"]) == 0
    out = capsys.readouterr().out
    assert main([*cli, "version", "conflicts", "bob_fix", "--no-header"]) == 0
    out = capsys.readouterr().out
    assert out.startswith(f"feature\t{fault}\tunsolved\t") and "vrtx" in out.split("\t")[3]
    assert main([*cli, "version", "merge", "bob_fix"]) == 1  # no silent merge
    err = capsys.readouterr().err
    assert "tgsis: error:" in err and str(fault) in err
    assert _z(db_dsn, fault) == (5.0, original[BOB, 2])

    if solution == "manual":  # check the child's state out, make it hold both edits, check it in there
        merged = tmp_path / "merged.ts"
        assert main([*cli, "--in", "bob_fix", "checkout", str(fault), str(merged)]) == 0
        _edit_file(merged, {ANN: 5.0})
        assert main([*cli, "checkin", str(merged)]) == 0
        assert "into version bob_fix" in capsys.readouterr().out
    if solution != "manual":  # taking one side's object throws the other's edit away: said, and asked for by name
        assert main([*cli, "version", "resolve", "bob_fix", "feature", str(fault), solution]) == 1
        err = capsys.readouterr().err
        assert "--discard-other" in err and "vrtx: 1 changed (1 value)" in err
        assert main([*cli, "version", "resolve", "bob_fix", "feature", str(fault), solution, "--discard-other"]) == 0
        assert "discarded the " in capsys.readouterr().out
    else:
        assert main([*cli, "version", "resolve", "bob_fix", "feature", str(fault), solution]) == 0
    assert main([*cli, "version", "merge", "bob_fix", "--remove"]) == 0
    assert "version removed" in capsys.readouterr().out
    expected = {"parent": (5.0, original[BOB, 2]), "child": (original[ANN, 2], -5.0), "manual": (5.0, -5.0)}
    assert _z(db_dsn, fault) == expected[solution]


def test_a_record_that_cannot_take_the_child_path(
    db_dsn: str, fault: int, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A check-out record whose frozen revision compress removed: a clear refusal naming the way out."""
    cli = ["--dsn", db_dsn]
    bob = tmp_path / "bob.ts"
    assert main([*cli, "checkout", str(fault), str(bob)]) == 0
    with psycopg.connect(db_dsn) as conn:
        tgsis.save_feature(
            conn,
            "faults",
            fault,
            tgsis.Surface(_surface().vertices + 1, _surface().cells, vertex_properties=_surface().vertex_properties),
        )
    assert main([*cli, "version", "compress"]) == 0
    _edit_file(bob, {BOB: -5.0})
    capsys.readouterr()
    assert main([*cli, "checkin", str(bob), "--on-conflict", "child"]) == 1
    err = capsys.readouterr().err
    assert f"feature {fault} was changed in version 'DEFAULT'" in err and "does not exist" in err
    assert "check out again" in err and "Traceback" not in err
    with psycopg.connect(db_dsn) as conn:
        assert [v.name for v in tgsis.list_versions(conn)] == ["DEFAULT"]


def test_a_child_version_named_in_free_text_gets_commands_that_run(
    db_dsn: str, fault: int, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A version name with blanks and a quote (free text, as the design's): the commands printed after the conflict
    are quoted for the shell, so that pasting them runs them on that version."""
    import shlex

    cli = ["--dsn", db_dsn]
    ann, bob = tmp_path / "ann.ts", tmp_path / "bob.vtu"
    assert main([*cli, "checkout", str(fault), str(bob)]) == 0
    assert main([*cli, "checkout", str(fault), str(ann)]) == 0
    _edit_file(ann, {ANN: 5.0})
    assert main([*cli, "checkin", str(ann)]) == 0
    _edit_file(bob, {BOB: -5.0})
    capsys.readouterr()
    assert (
        main([*cli, "checkin", str(bob), "--on-conflict", "child", "--child-version", "Bob's fix; 2024", "--json"]) == 0
    )
    doc = json.loads(capsys.readouterr().out)
    assert doc["version"] == "Bob's fix; 2024" and doc["conflict"]
    conflicts, resolve, merge = (shlex.split(c) for c in doc["commands"])
    assert conflicts == ["tgsis", "version", "conflicts", "Bob's fix; 2024", "--rows"]
    assert main([*cli, *conflicts[1:]]) == 0
    assert f"feature\t{fault}\t" in capsys.readouterr().out
    assert resolve[:6] == ["tgsis", "version", "resolve", "Bob's fix; 2024", "feature", str(fault)]
    assert main([*cli, *resolve[1:6], "child", "--discard-other"]) == 0
    assert f"feature {fault} in 'Bob''s fix; 2024': child" in capsys.readouterr().out
    assert main([*cli, *merge[1:]]) == 0
    assert "merged 'Bob''s fix; 2024' into its parent" in capsys.readouterr().out
