"""tgsis.export_conflict and ``tgsis version conflicts --export DIR``: a conflict's three states as files (issue 39)."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt
import psycopg
import pytest
from psycopg.conninfo import make_conninfo

import tgsis
from tests.merge_data import SIDE, curved_surface, make_fault, move
from tests.roles import login_roles
from tgsis import formats
from tgsis.cli import main
from tgsis.db import features as F
from tgsis.merge3 import MeshState

Conn = psycopg.Connection[Any]


def _conflicting_edits(conn: Conn, geoid: int) -> None:
    """The child moves 50-52 up and one end sideways; the parent moves 52-53 down and removes vertex 0
    (with its triangles): parent file indices are then shifted by one against the ids."""
    move(conn, "e1", geoid, [50, 51, 52], (0.0, 0.0, 5.0))
    move(conn, "e1", geoid, np.arange((SIDE - 2) * SIDE, SIDE * SIDE), (0.0, 2.0, 0.0))
    move(conn, "DEFAULT", geoid, [52, 53], (0.0, 0.0, -4.0))
    with tgsis.in_version(conn, "DEFAULT"):
        conn.execute("DELETE FROM tgsis.trgl WHERE geoid = %s AND 0 IN (vrtxid1, vrtxid2, vrtxid3)", (geoid,))
        conn.execute("DELETE FROM tgsis.vrtx WHERE geoid = %s AND vrtxid = 0", (geoid,))
    conn.commit()


@pytest.fixture
def fault(conn: Conn, fault_clone: int) -> int:
    geoid = fault_clone  # make_fault's, built once (tests/conftest.py)
    _conflicting_edits(conn, geoid)
    return geoid


def _read_back(path: Path) -> tgsis.Mesh:
    """A written state with its cell values: from the file, or for GOCAD from the CSV beside it."""
    mesh = formats.read_one(path)
    cells = path.with_name(path.stem + "_cells.csv")
    if path.suffix in (".ts", ".pl", ".vs", ".so"):
        assert cells.exists()
        header, *rows = [line.split(",") for line in cells.read_text().splitlines()]
        assert len(rows) == len(mesh.cells)
        for i, name in enumerate(header):
            mesh.cell_properties[name] = np.array([float(r[i]) for r in rows])
    else:
        assert not cells.exists()
    return mesh


def _same_as_state(mesh: tgsis.Mesh, state: MeshState, *, depth: bool = False) -> None:
    """The file's mesh is the state: vertex i = i-th id ascending (vrtxid), coordinates bit for bit, cells, values."""
    assert mesh.vertex_properties["vrtxid"].astype(np.int64).tolist() == state.vertex_ids.tolist()
    expected = state.vertices.copy()
    if depth:
        expected[:, 2] = -expected[:, 2]
    assert mesh.vertices.tobytes() == expected.tobytes()
    ids = mesh.vertex_properties["vrtxid"].astype(np.int64)
    assert mesh.cell_properties["trglid"].astype(np.int64).tolist() == state.cell_ids.tolist()
    np.testing.assert_array_equal(ids[mesh.cells], state.cells)
    for name, values in state.vertex_properties.items():
        assert (
            np.asarray(mesh.vertex_properties[name], dtype=np.float64).tobytes() == values.astype(np.float64).tobytes()
        )
    for name, values in state.cell_properties.items():
        assert np.asarray(mesh.cell_properties[name], dtype=np.float64).tobytes() == values.astype(np.float64).tobytes()
    assert set(mesh.vertex_properties) == {*state.vertex_properties, "vrtxid"}
    assert set(mesh.cell_properties) == {*state.cell_properties, "trglid"}


@pytest.mark.parametrize("ext", ["ts", "vtu", "vtp", "ply"])
def test_the_three_files_read_back_as_the_three_states(conn: Conn, fault: int, tmp_path: Path, ext: str) -> None:
    written = tgsis.export_conflict(
        conn, "e1", fault, tmp_path / "out", format=None if ext == "ts" else ext, picture=False
    )
    names = [p.name for p in written]
    sides = [
        f"{fault}_fault_{s}{e}"
        for s in ("base", "parent", "child")
        for e in ([f".{ext}", "_cells.csv"] if ext == "ts" else [f".{ext}"])
    ]
    assert names == [*sides, f"{fault}_regions.json"]
    assert sorted(p.name for p in (tmp_path / "out").iterdir()) == sorted(names)  # no scratch folder left
    merge = tgsis.object_merge(conn, "e1", fault)
    assert merge.conflicts and merge.parent.vertex_ids[0] == 1  # the parent lost vertex 0: indices != ids
    for path, state in zip(
        [p for p in written if p.suffix == f".{ext}"], (merge.base, merge.parent, merge.child), strict=True
    ):
        mesh = _read_back(path)
        assert isinstance(mesh, tgsis.Surface)
        assert mesh.name == ("fault" if ext != "ply" else None)  # a PLY file holds no name: the file name has it
        _same_as_state(mesh, state)
    assert formats.read_one(written[0]).vertices.tobytes() == curved_surface().vertices.tobytes()


def test_a_depth_surface_stays_depth(conn: Conn, tmp_path: Path) -> None:
    geoid = make_fault(conn, {"zpositive": "Depth"})
    _conflicting_edits(conn, geoid)
    written = tgsis.export_conflict(conn, "e1", geoid, tmp_path, picture=False)
    merge = tgsis.object_merge(conn, "e1", geoid)
    for path, state in zip(written[0:6:2], (merge.base, merge.parent, merge.child), strict=True):
        mesh = _read_back(path)
        assert mesh.metadata["zpositive"] == "Depth"
        _same_as_state(mesh, state, depth=True)
    assert "ZPOSITIVE Depth" in written[0].read_text()
    # the base file holds the depths the user gave, as given
    assert formats.read_one(written[0]).vertices.tobytes() == curved_surface().vertices.tobytes()


@pytest.fixture
def cli_state(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("TGSIS_HOME", str(tmp_path / "home"))
    monkeypatch.delenv("TGSIS_VERSION", raising=False)


def _cli(dsn: str, capsys: pytest.CaptureFixture[str], *argv: str) -> str:
    assert main(["--dsn", dsn, *argv]) == 0, capsys.readouterr()
    return capsys.readouterr().out


@pytest.mark.usefixtures("cli_state")
def test_cli_export_writes_the_files_and_regions_equal_to_regions_json(
    conn: Conn, fault: int, db_dsn: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "made" / "here"  # made when missing
    text = _cli(db_dsn, capsys, "version", "conflicts", "e1", "--export", str(out))
    stems = [f"{fault}_fault_{s}.ts" for s in ("base", "parent", "child")]
    stems = [n for s in stems for n in (s, s.replace(".ts", "_cells.csv"))]
    expected = [*stems, f"{fault}_regions.json", f"{fault}_fault_overlay.png"]
    for name in expected:
        assert f"wrote {out / name}" in text.splitlines()
    assert sorted(p.name for p in out.iterdir()) == sorted(expected)
    listed = json.loads(_cli(db_dsn, capsys, "version", "conflicts", "e1", "--regions", "--json"))
    [entry] = listed["conflicts"]
    assert json.loads((out / f"{fault}_regions.json").read_text()) == entry["regions"]
    again = json.loads(_cli(db_dsn, capsys, "version", "conflicts", "e1", "--export", str(out), "--force", "--json"))
    assert again["conflicts"][0]["exported"] == {"files": [str(out / n) for n in expected]}


@pytest.mark.usefixtures("cli_state")
def test_cli_export_refuses_existing_files_and_writes_nothing(
    conn: Conn, fault: int, db_dsn: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "out"
    out.mkdir()
    taken = out / f"{fault}_fault_child.ts"
    taken.write_text("mine\n")
    assert main(["--dsn", db_dsn, "version", "conflicts", "e1", "--export", str(out)]) != 0
    captured = capsys.readouterr()
    assert taken.name in captured.err and "--force" in captured.err and "nothing was written" in captured.err
    assert [p.name for p in out.iterdir()] == [taken.name] and taken.read_text() == "mine\n"
    _cli(db_dsn, capsys, "version", "conflicts", "e1", "--export", str(out), "--force")
    assert taken.read_text() != "mine\n" and len(list(out.iterdir())) == 8


@pytest.mark.usefixtures("cli_state")
def test_cli_export_refuses_a_format_before_making_the_folder(
    conn: Conn, fault: int, db_dsn: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # was: exit 0, every object "no files: no file format has the extension 'xyz'", and DIR made and left empty
    out = tmp_path / "made" / "here"
    assert main(["--dsn", db_dsn, "version", "conflicts", "e1", "--export", str(out), "--format", "xyz"]) != 0
    err = capsys.readouterr().err
    assert "no file format has the extension 'xyz'" in err and "--format" in err
    assert list(tmp_path.iterdir()) == []


@pytest.mark.usefixtures("cli_state")
def test_cli_export_that_fails_midway_leaves_no_folder_it_made(
    conn: Conn, fault: int, db_dsn: str, tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: Any
) -> None:
    # a write that fails (here: the disk is full) after the folder was made: the folders made go again
    def disk_full(*args: Any, **kwargs: Any) -> list[Path]:
        raise OSError(28, "No space left on device")

    monkeypatch.setattr("tgsis.cli.commands.versions.export_conflict", disk_full)
    out = tmp_path / "made" / "here"
    assert main(["--dsn", db_dsn, "version", "conflicts", "e1", "--export", str(out)]) != 0
    assert "No space left on device" in capsys.readouterr().err
    assert list(tmp_path.iterdir()) == []


def test_export_conflict_refuses_existing_files_and_writes_nothing(conn: Conn, fault: int, tmp_path: Path) -> None:
    taken = tmp_path / f"{fault}_regions.json"
    taken.write_text("{}")
    with pytest.raises(tgsis.InvalidInputError, match=f"{fault}_regions.json.*nothing was written"):
        tgsis.export_conflict(conn, "e1", fault, tmp_path, picture=False)
    assert [p.name for p in tmp_path.iterdir()] == [taken.name] and taken.read_text() == "{}"
    tgsis.export_conflict(conn, "e1", fault, tmp_path, picture=False, overwrite=True)
    assert json.loads(taken.read_text())["regions"]


def test_a_format_that_cannot_hold_the_kind_is_refused(conn: Conn, fault: int, tmp_path: Path) -> None:
    with pytest.raises(tgsis.InvalidInputError, match=r"\.vs.*SURFACE"):
        tgsis.export_conflict(conn, "e1", fault, tmp_path, format="vs", picture=False)
    with pytest.raises(tgsis.InvalidInputError, match="no file format has the extension 'xyz'"):
        tgsis.export_conflict(conn, "e1", fault, tmp_path, format="xyz", picture=False)
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("geotype", ["MULTIPOINT", "MULTILINESTRING", "MULTITETRA"])
def test_other_kinds_are_written_as_their_gocad_files(conn: Conn, tmp_path: Path, geotype: str) -> None:
    from tests.test_object_merge import _other_kind

    F.create_feature_class(conn, "bodies", geotype)
    tgsis.enable_feature_versioning(conn)
    geoid = F.insert_feature(conn, "bodies", _other_kind(geotype))
    tgsis.create_version(conn, "e1")
    conn.commit()
    move(conn, "e1", geoid, [1, 2], (0.5, 0.25, -1.125))
    move(conn, "DEFAULT", geoid, [2, 3], (-3.3, 0.0, 2.2))
    conn.commit()
    written = tgsis.export_conflict(conn, "e1", geoid, tmp_path, picture=True)
    ext = {"MULTIPOINT": "vs", "MULTILINESTRING": "pl", "MULTITETRA": "so"}[geotype]
    assert [p.suffix for p in written] == [f".{ext}", ".csv"] * 3 + [".json", ".png"]
    merge = tgsis.object_merge(conn, "e1", geoid)
    key = {"MULTIPOINT": "pointid", "MULTILINESTRING": "segid", "MULTITETRA": "tetraid"}[geotype]
    for path, state in zip(written[0:6:2], (merge.base, merge.parent, merge.child), strict=True):
        mesh = _read_back(path)
        assert mesh.geotype.value == geotype
        assert mesh.vertices.tobytes() == state.vertices.tobytes()
        assert mesh.cell_properties[key].astype(np.int64).tolist() == state.cell_ids.tolist()
        ids = mesh.vertex_properties["vrtxid"].astype(np.int64)
        np.testing.assert_array_equal(ids[mesh.cells], state.cells)


def _pixels_near(image: npt.NDArray[Any], colour: str) -> int:
    rgb = np.array([int(colour[i : i + 2], 16) for i in (1, 3, 5)]) / 255.0
    return int((np.abs(image[:, :, :3] - rgb).max(axis=2) < 0.06).sum())


def test_the_png_overlay_shows_both_sides_and_the_conflict(conn: Conn, fault: int, tmp_path: Path) -> None:
    from matplotlib import image as mpimg

    from tgsis.pictures import OVERLAY_COLOURS

    written = tgsis.export_conflict(conn, "e1", fault, tmp_path)
    png = written[-1]
    assert png.name == f"{fault}_fault_overlay.png" and png.stat().st_size > 1000
    picture = mpimg.imread(png)
    counts = {k: _pixels_near(picture, c) for k, c in OVERLAY_COLOURS.items()}
    assert counts["base"] > 2000  # the grey surface
    assert counts["parent"] > 50 and counts["child"] > 50 and counts["conflict"] > 50
    # the child edited more (a whole end) than the parent: more orange than blue
    assert counts["child"] > counts["parent"]


@pytest.mark.usefixtures("cli_state")
def test_a_role_without_rights_gets_the_permission_error_and_no_files(
    conn: Conn, fault: int, db_dsn: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    conn.execute("REVOKE SELECT ON public.faults FROM tgsis_reader")
    conn.commit()
    out = tmp_path / "out"
    with login_roles(db_dsn, {"rita": "tgsis_reader"}) as made:
        with pytest.raises(tgsis.MissingPrivilegeError, match="faults"):
            tgsis.export_conflict(made.connect("rita"), "e1", fault, out)
        assert not out.exists()
        rita_dsn = make_conninfo(db_dsn, user=made.name("rita"))
        assert main(["--dsn", rita_dsn, "version", "conflicts", "e1", "--export", str(out)]) != 0
        captured = capsys.readouterr()
        assert "permission denied" in captured.err and "faults" in captured.err
        assert not out.exists() or list(out.iterdir()) == []


@pytest.mark.usefixtures("cli_state")
def test_force_and_format_need_export(conn: Conn, fault: int, db_dsn: str, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["--dsn", db_dsn, "version", "conflicts", "e1", "--force"]) != 0
    assert "--force" in capsys.readouterr().err


@pytest.mark.usefixtures("cli_state")
def test_cli_says_why_no_files_are_written_for_a_row_that_is_no_mesh(
    conn: Conn, fault: int, db_dsn: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    conn.execute("CREATE TABLE wells (id int PRIMARY KEY, depth float8)")
    conn.execute("INSERT INTO wells VALUES (1, 1000.0)")
    conn.commit()
    tgsis.enable_versioning(conn, "wells", "id", "well")
    tgsis.create_version(conn, "w1")
    conn.commit()
    with tgsis.in_version(conn, "w1"):
        conn.execute("UPDATE wells SET depth = 1250 WHERE id = 1")
    with tgsis.in_version(conn, "DEFAULT"):
        conn.execute("UPDATE wells SET depth = 1300 WHERE id = 1")
    conn.commit()
    out = tmp_path / "out"
    text = _cli(db_dsn, capsys, "version", "conflicts", "w1", "--export", str(out))
    assert "well 1: no files: a row of well, not a mesh" in text.splitlines()
    assert not any(out.iterdir())
    document = json.loads(_cli(db_dsn, capsys, "version", "conflicts", "w1", "--export", str(out), "--json"))
    assert document["conflicts"][0]["exported"] == {"files": [], "reason": "no files: a row of well, not a mesh"}


def test_a_real_cfm_fault_with_an_atom_round_trips(conn: Conn, tmp_path: Path) -> None:
    """The file a real tool wrote (two TFACE parts, an ATOM, a CRS block): the three files read back as stored."""
    from tests.shared_data import cfm

    [source] = formats.read(cfm("formats/WTRA-NCFS-PPT-Pitas_Point_fault.ts"))
    assert source.metadata.get("gocad_atoms")
    F.create_feature_class(conn, "faults", "SURFACE")
    tgsis.enable_feature_versioning(conn)
    source.vertex_properties.clear()
    geoid = F.insert_feature(conn, "faults", source)
    tgsis.create_version(conn, "e1")
    conn.commit()
    move(conn, "e1", geoid, [3, 4], (0.0, 0.0, 5.5))
    move(conn, "DEFAULT", geoid, [4, 5], (1.25, 0.0, 0.0))
    conn.commit()
    written = tgsis.export_conflict(conn, "e1", geoid, tmp_path, picture=False)
    merge = tgsis.object_merge(conn, "e1", geoid)
    assert merge.conflicts and "refid" in merge.base.vertex_properties
    depth = source.metadata.get("zpositive") == "Depth"
    for path, state in zip(written[0:6:2], (merge.base, merge.parent, merge.child), strict=True):
        mesh = _read_back(path)
        assert mesh.name == source.name
        assert mesh.metadata.get("zpositive") == source.metadata.get("zpositive")
        assert mesh.metadata.get("gocad_coordinate_system") == source.metadata.get("gocad_coordinate_system")
        _same_as_state(mesh, state, depth=depth)
    assert _read_back(written[0]).vertices.tobytes() == source.vertices.tobytes()


@pytest.mark.usefixtures("cli_state")
def test_without_matplotlib_the_pngs_are_skipped_with_a_notice(
    conn: Conn,
    fault: int,
    db_dsn: str,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    import sys

    monkeypatch.setitem(sys.modules, "matplotlib", None)  # Python then refuses to import it, as when not installed
    out = tmp_path / "out"
    assert main(["--dsn", db_dsn, "version", "conflicts", "e1", "--export", str(out)]) == 0
    captured = capsys.readouterr()
    [notice] = [line for line in captured.err.splitlines() if "notice" in line]
    assert "no PNG overlays" in notice and "matplotlib" in notice and "tgsis[pictures]" in notice
    names = sorted(p.name for p in out.iterdir())
    assert len(names) == 7 and not any(n.endswith(".png") for n in names)
    assert sum(line.startswith("wrote ") for line in captured.out.splitlines()) == 7
