"""The G-map commands (`tgsis gmap import|check|cells|at`, `tgsis extrude`, `tgsis slice`) against a real database."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import psycopg
import pytest
import pyvista as pv

from tgsis import formats
from tgsis.cli import main
from tgsis.mesh import Surface, TetraMesh

from .gmaps_shapes import block_tetrahedra, grid


def _run(capsys: pytest.CaptureFixture[str], *args: str) -> tuple[int, str, str]:
    code = main(list(args))
    out, err = capsys.readouterr()
    return code, out, err


@pytest.fixture
def files(tmp_path: Path) -> dict[str, Path]:
    vertices, triangles = grid(4, 3)
    horizon = Surface(
        vertices, triangles, name="horizon", cell_properties={"change_m": np.arange(len(triangles), dtype=float)}
    )
    formats.write(horizon, tmp_path / "horizon.vtu")
    tv, tt = block_tetrahedra(2)
    formats.write(
        TetraMesh(tv, tt, name="block", cell_properties={"facies": np.arange(len(tt), dtype=np.int32)}),
        tmp_path / "block.vtu",
    )
    return {"horizon": tmp_path / "horizon.vtu", "block": tmp_path / "block.vtu"}


def test_import_check_cells_and_a_snapshot_for_paraview(
    db_dsn: str, files: dict[str, Path], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    dsn = ["--dsn", db_dsn]
    assert (
        _run(
            capsys,
            *dsn,
            "class",
            "create",
            "blocks",
            "--geotype",
            "GMAP",
            "--time-model",
            "GMAP",
            "--cell-level",
            "3",
            "--property",
            "facies:int",
        )[0]
        == 0
    )
    code, out, _ = _run(capsys, *dsn, "gmap", "import", str(files["block"]), "--class", "blocks", "--json")
    assert code == 0
    stored = json.loads(out)
    assert stored["dimension"] == 3 and stored["cells"][3] == 48 and stored["darts"] == 48 * 24
    geoid = str(stored["id"])
    code, out, err = _run(capsys, *dsn, "gmap", "check", geoid)
    assert code == 0 and out == "" and "a valid G-map" in err
    code, out, _ = _run(capsys, *dsn, "gmap", "cells", geoid, "2", "--at", "0", "--json")
    assert json.loads(out)["cells"] > 48
    code, out, _ = _run(capsys, *dsn, "gmap", "at", geoid, "5", str(tmp_path / "block_at_5.vtu"))
    assert code == 0 and "3-G-map in R^3 with 1152 darts" in out
    grid_ = pv.read(tmp_path / "block_at_5.vtu")
    assert grid_.n_cells == 48 and list(grid_.cell_data["facies"]) == list(range(48))
    assert np.isclose(np.abs(grid_.compute_cell_sizes()["Volume"]).sum(), 8.0)
    # a broken map: exit 1, the darts named
    with psycopg.connect(db_dsn) as conn:
        conn.execute(
            "UPDATE tgsis.gmap_alpha SET dartid2 = dartid WHERE geoid = %s AND level = 0 AND dartid = 7", (int(geoid),)
        )
    code, out, err = _run(capsys, *dsn, "gmap", "check", geoid, "--json")
    report = json.loads(out)
    assert code == 1 and not report["valid"]
    assert any(7 in p["darts"] and "free in alpha_0" in p["problem"] for p in report["problems"])


def test_extrude_a_file_along_knowledge_then_slice_it_back(
    db_dsn: str, files: dict[str, Path], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    dsn = ["--dsn", db_dsn]
    assert (
        _run(
            capsys,
            *dsn,
            "class",
            "create",
            "history",
            "--geotype",
            "GMAP",
            "--time-model",
            "MULTIDIM",
            "--cell-level",
            "3",
            "--property",
            "change_m:float8",
        )[0]
        == 0
    )
    code, out, _ = _run(
        capsys,
        *dsn,
        "extrude",
        str(files["horizon"]),
        "--axis",
        "knowledge",
        "--values",
        "2019,2021,2023",
        "--class",
        "history",
        "--output",
        str(tmp_path / "history.vtu"),
        "--json",
    )
    assert code == 0
    result = json.loads(out)
    assert result["axes"] == ["x", "y", "z", "knowledge"] and result["dimension"] == 3
    assert result["cells"][3] == 2 * 24  # 24 triangles x 2 intervals
    prisms = pv.read(tmp_path / "history.vtu")
    assert prisms.n_cells == 48 and sorted(set(prisms.point_data["knowledge"])) == [2019.0, 2021.0, 2023.0]
    code, out, _ = _run(
        capsys,
        *dsn,
        "slice",
        str(result["id"]),
        "--axis",
        "knowledge",
        "--value",
        "2021",
        "--output",
        str(tmp_path / "h2021.vtu"),
    )
    assert code == 0 and "2-G-map in R^3" in out
    section = pv.read(tmp_path / "h2021.vtu")
    assert section.n_cells == 24 and np.isclose(section.compute_cell_sizes()["Area"].sum(), 1.0)  # the unit square


def test_bad_arguments_are_refused_in_the_commands_terms(
    db_dsn: str, files: dict[str, Path], capsys: pytest.CaptureFixture[str]
) -> None:
    dsn = ["--dsn", db_dsn]
    code, _, err = _run(capsys, *dsn, "extrude", str(files["horizon"]), "--axis", "k", "--values", "0,1")
    assert code == 1 and "--class" in err and "--output" in err
    code, _, err = _run(
        capsys, *dsn, "extrude", str(files["horizon"]), "--axis", "z", "--values", "0,1", "--output", "x.vtu"
    )
    assert code == 1 and "--axis 'z' is an axis of the source already" in err
    code, _, err = _run(
        capsys, *dsn, "extrude", str(files["horizon"]), "--axis", "k", "--values", "0,x", "--output", "x.vtu"
    )
    assert code == 1 and "--values '0,x' must be numbers" in err
    code, _, err = _run(capsys, *dsn, "class", "create", "nolevel", "--geotype", "GMAP", "--time-model", "GMAP")
    assert code == 1 and "needs the level of the cells" in err and "--cell-level 0 (vertices)" in err


def test_ls_names_a_gmaps_darts_as_darts(
    db_dsn: str, files: dict[str, Path], capsys: pytest.CaptureFixture[str]
) -> None:
    """`ls` of a G-map: its 1152 darts in the darts column, not as 1152 cells (it has 48 volumes)."""
    dsn = ["--dsn", db_dsn]
    assert (
        _run(
            capsys,
            *dsn,
            "class",
            "create",
            "blocks",
            "--geotype",
            "GMAP",
            "--time-model",
            "GMAP",
            "--cell-level",
            "3",
            "--property",
            "facies:int",
        )[0]
        == 0
    )
    code, out, _ = _run(capsys, *dsn, "gmap", "import", str(files["block"]), "--class", "blocks", "--json")
    geoid = json.loads(out)["id"]
    code, out, _ = _run(capsys, *dsn, "ls")
    assert code == 0
    header, row = (line.split("\t") for line in out.splitlines())
    assert header == ["id", "class", "name", "geotype", "vertices", "cells", "members", "darts", "properties"]
    assert row[0] == str(geoid) and row[3] == "GMAP" and row[5] == "" and row[7] == "1152"
    code, out, _ = _run(capsys, *dsn, "ls", "--json")
    [feature] = json.loads(out)["features"]
    assert feature["cells"] is None and feature["darts"] == 1152
