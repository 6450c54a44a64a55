"""`tgsis checkout` / `tgsis checkin` against a real database: edit a file, check it in, conflicts."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import psycopg
import pytest

import tgsis
from tgsis import formats
from tgsis.cli import main


def _surface() -> tgsis.Surface:
    u, v = np.meshgrid(np.arange(12, dtype=float), np.arange(12, dtype=float))
    vertices = np.stack([u.ravel() * 10.5, v.ravel() * 3.25, np.sin(u.ravel()) / 3], axis=1)
    idx = np.arange(144).reshape(12, 12)
    a, b, c, d = idx[:-1, :-1].ravel(), idx[:-1, 1:].ravel(), idx[1:, :-1].ravel(), idx[1:, 1:].ravel()
    return tgsis.Surface(
        vertices,
        np.concatenate([np.stack([a, b, d], 1), np.stack([a, d, c], 1)]),
        vertex_properties={"porosity": np.linspace(0.1, 0.3, 144)},
        name="f1",
    )


@pytest.fixture
def fault(db_dsn: str) -> int:
    with psycopg.connect(db_dsn) as conn:
        tgsis.create_feature_class(
            conn, "faults", "SURFACE", cell_properties={"porosity": "float8"}, feature_properties={"author": "text"}
        )
        tgsis.enable_feature_versioning(conn)
        return tgsis.insert_feature(conn, "faults", _surface())


def _edit_file(path: Path, z: float, vertex: int) -> None:
    """What a desktop tool does: read the file, move one vertex, write it back."""
    mesh = formats.read_one(path)
    mesh.vertices[vertex, 2] = z
    formats.write(mesh, path)


def _stored(dsn: str, fid: int, version: str = "DEFAULT") -> tgsis.Mesh:
    with psycopg.connect(dsn) as conn, tgsis.in_version(conn, version):
        mesh = tgsis.fetch_feature(conn, "faults", fid).mesh
    assert isinstance(mesh, tgsis.Mesh)
    return mesh


def test_checkout_edit_checkin_twice(
    db_dsn: str, fault: int, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = tmp_path / "fault.ts"
    assert main(["--dsn", db_dsn, "checkout", str(fault), str(path)]) == 0
    out = capsys.readouterr().out
    assert f"checked out feature {fault} (faults, 144 vertices, 242 triangles) of version DEFAULT" in out
    assert (tmp_path / "fault.ts.tgsis-checkout.npz").is_file()
    _edit_file(path, 9.0, 13)
    assert main(["--dsn", db_dsn, "checkin", str(path), "--set", "author=ann"]) == 0
    out = capsys.readouterr().out
    assert f"checked in feature {fault} into version DEFAULT" in out
    assert "143 kept, 1 moved, 0 removed, 0 added" in out
    # the triangles around the moved vertex are the same triangles (compared by content, as they are stored)
    assert "triangles: 242 kept (6 of them on moved vertices), 0 removed, 0 added" in out
    stored = _stored(db_dsn, fault)
    assert stored.vertices[13, 2] == 9.0 and np.array_equal(
        np.delete(stored.vertices, 13, 0), np.delete(_surface().vertices, 13, 0)
    )
    # the record followed the new state: edit again, check in again
    _edit_file(path, -9.0, 20)
    assert main(["--dsn", db_dsn, "checkin", str(path)]) == 0
    capsys.readouterr()
    stored = _stored(db_dsn, fault)
    assert stored.vertices[13, 2] == 9.0 and stored.vertices[20, 2] == -9.0
    with psycopg.connect(db_dsn) as conn:
        assert tgsis.fetch_feature(conn, "faults", fault).properties == {"author": "ann"}


def test_second_writer_is_refused_then_goes_to_a_child(
    db_dsn: str, fault: int, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    ann, bob = tmp_path / "ann.vtu", tmp_path / "bob.ts"
    assert main(["--dsn", db_dsn, "checkout", str(fault), str(ann)]) == 0
    assert main(["--dsn", db_dsn, "checkout", str(fault), str(bob)]) == 0
    _edit_file(ann, 5.0, 1)
    _edit_file(bob, -5.0, 100)
    assert main(["--dsn", db_dsn, "checkin", str(ann)]) == 0
    capsys.readouterr()
    assert main(["--dsn", db_dsn, "checkin", str(bob)]) == 1
    err = capsys.readouterr().err
    assert f"feature {fault} was changed in version 'DEFAULT' since it was checked out" in err
    assert "--on-conflict child" in err
    assert _stored(db_dsn, fault).vertices[100, 2] != -5.0  # Bob's edit was not written...
    assert main(["--dsn", db_dsn, "checkin", str(bob), "--on-conflict", "child", "--child-version", "bob_fix"]) == 0
    out = capsys.readouterr().out
    assert "into version bob_fix (a new child version" in out and "tgsis version merge bob_fix" in out
    mine = _stored(db_dsn, fault, "bob_fix")  # ...but it is not lost
    assert mine.vertices[100, 2] == -5.0 and mine.vertices[1, 2] != 5.0
    assert _stored(db_dsn, fault).vertices[1, 2] == 5.0  # and Ann's stays in DEFAULT


def test_checkin_errors(db_dsn: str, fault: int, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = tmp_path / "f.ts"
    cases = [
        (["checkin", str(path)], "was not checked out here"),
        (["checkout", "999", str(path)], "no feature class has a feature 999"),
    ]
    for argv, message in cases:
        assert main(["--dsn", db_dsn, *argv]) == 1, argv
        err = capsys.readouterr().err
        assert err.startswith("tgsis: error: ") and message in err and "Traceback" not in err, (argv, err)
    assert main(["--dsn", db_dsn, "checkout", str(fault), str(path)]) == 0
    assert main(["--dsn", db_dsn, "checkin", str(path), "--tolerance", "-1"]) == 1
    assert "--tolerance must be" in capsys.readouterr().err
    path.write_text("GOCAD TSurf 1\nHEADER {\nname:broken\n}\nTFACE\nVRTX 1 0 0\nEND\n")
    assert main(["--dsn", db_dsn, "checkin", str(path)]) == 1
    assert "tgsis: error:" in capsys.readouterr().err


def test_checkin_counts_triangles_by_content(
    db_dsn: str, fault: int, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Moved vertices keep their triangles; a triangle really cut out is one removed, in the text and in --json."""
    path = tmp_path / "fault.ts"
    assert main(["--dsn", db_dsn, "checkout", str(fault), str(path)]) == 0
    mesh = formats.read_one(path)
    mesh.vertices[[13, 20], 2] = [9.0, -9.0]
    cells = np.delete(mesh.cells, 100, axis=0)  # a triangle of neither moved vertex
    assert not np.isin(mesh.cells[100], [13, 20]).any()
    on_moved = int(np.isin(cells, [13, 20]).any(axis=1).sum())
    assert on_moved == 12
    formats.write(
        tgsis.Surface(
            mesh.vertices, cells, name=mesh.name, metadata=mesh.metadata, vertex_properties=mesh.vertex_properties
        ),
        path,
    )
    capsys.readouterr()
    assert main(["--dsn", db_dsn, "checkin", str(path), "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["vertices"] == {"kept": 142, "moved": 2, "removed": 0, "added": 0}
    assert doc["cells"] == {"kept": 241, "removed": 1, "added": 0, "on_moved_vertices": 12}
    stored = _stored(db_dsn, fault)
    assert stored.n_cells == 241 and stored.vertices[20, 2] == -9.0


def test_checkout_of_a_feature_missing_from_the_version_names_the_version(
    db_dsn: str, fault: int, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Issue 38: "no feature class has a feature 7" left users looking for a typo; the feature was deleted in
    (or never made it to) the version they work in, and the message now says which version."""
    with psycopg.connect(db_dsn) as conn:
        tgsis.create_version(conn, "cfm6")
        with tgsis.in_version(conn, "cfm6"):
            tgsis.delete_feature(conn, "faults", fault)
            only_here = tgsis.insert_feature(conn, "faults", _surface())
        conn.commit()
    capsys.readouterr()
    for where, fid, extra in (
        (["--in", "cfm6"], fault, []),
        (["--in", "cfm6"], fault, ["--class", "faults"]),
        ([], only_here, []),
    ):
        file = tmp_path / f"f{fid}_{len(extra)}.ts"
        assert main(["--dsn", db_dsn, *where, "checkout", str(fid), str(file), *extra]) == 1
        err = capsys.readouterr().err
        version = "cfm6" if where else "DEFAULT"
        assert f"feature {fid}" in err and f"in version {version}" in err, err
        assert not file.exists()
