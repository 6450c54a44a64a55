"""`tgsis import` and `tgsis export` take the VTK files of ParaView and pyvista: .vtp, legacy .vtk, .vtu.

The formats are registered in tgsis.formats.FORMATS, which the command line
uses; this checks it end to end: a surface pyvista saved is imported, exported
to each VTK file, and what pyvista and meshio read back is what was stored. The
feature ids are taken from the database, not from the command's output (whose
layout is not this test's concern).
"""

from __future__ import annotations

from pathlib import Path
from typing import cast

import meshio
import numpy as np
import psycopg
import pytest
import pyvista as pv

from tgsis.cli import main


def stored(dsn: str) -> list[int]:
    with psycopg.connect(dsn) as conn:
        return [int(r[0]) for r in conn.execute("SELECT _geoid FROM horizons ORDER BY _geoid")]


def test_import_pyvista_files_and_export_every_vtk_file(
    db_dsn: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    sphere = pv.Sphere(theta_resolution=10, phi_resolution=8)
    sphere.point_data.clear()
    sphere["porosity"] = np.linspace(0, 1, sphere.n_points)
    assert (
        main(["--dsn", db_dsn, "class", "create", "horizons", "--geotype", "SURFACE", "--property", "porosity:float8"])
        == 0
    )
    for name in ("dome.vtp", "dome.vtk"):
        sphere.save(tmp_path / name)
        assert main(["--dsn", db_dsn, "import", str(tmp_path / name), "--class", "horizons"]) == 0, (
            capsys.readouterr().err
        )
    ids = stored(db_dsn)
    assert len(ids) == 2
    for target in ("out.vtp", "out.vtk", "out.vtu"):
        assert main(["--dsn", db_dsn, "export", str(ids[0]), str(tmp_path / target)]) == 0, capsys.readouterr().err
        # cast: mypy cannot narrow pyvista.read's DataSet | MultiBlock by isinstance (their vtk bases are untyped)
        back = cast(pv.DataSet, pv.read(tmp_path / target))
        assert isinstance(back, pv.DataSet)
        assert np.array_equal(back.points, sphere.points) and back.n_cells == sphere.n_cells
        assert np.array_equal(back["porosity"], sphere["porosity"])
        if target != "out.vtp":  # meshio reads no .vtp
            m = meshio.read(tmp_path / target)
            assert np.array_equal(m.cells_dict["triangle"], sphere.regular_faces)


def test_a_file_of_quads_is_refused_and_nothing_stored(
    db_dsn: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["--dsn", db_dsn, "class", "create", "horizons", "--geotype", "SURFACE"]) == 0
    plane = pv.Plane()
    plane.points[12, 2] = 0.05  # type: ignore[index]  # pyvista types __setitem__'s key int only
    # quads that are not planar (planar ones are split, issue 37)
    plane.save(tmp_path / "plane.vtk")
    capsys.readouterr()
    assert main(["--dsn", db_dsn, "import", str(tmp_path / "plane.vtk"), "--class", "horizons"]) == 1
    err = capsys.readouterr().err
    assert "plane.vtk: POLYDATA cell" in err and "is not planar" in err and "triangulate" in err
    assert stored(db_dsn) == []
