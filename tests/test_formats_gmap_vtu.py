"""G-maps for ParaView: the top cells of an n-G-map as VTK lines, polygons or polyhedra in a .vtu, read by VTK (pyvista)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import pyvista as pv

import tgsis
from tgsis import gmaps
from tgsis.formats.vtk import write_gmap_vtu

from .gmaps_shapes import block_tetrahedra


def test_polygons_of_any_size_and_their_properties(tmp_path: Path) -> None:
    square_and_triangle = gmaps.GMap.from_polygons(
        [[0.0, 0, 0], [1.0, 0, 0], [1.0, 1, 0], [0.0, 1, 0], [2, 0.5, 0]], [0, 1, 2, 3, 1, 4, 2], [0, 4, 7]
    )
    g = gmaps.GMap(
        square_and_triangle.alpha,
        square_and_triangle.vertex,
        square_and_triangle.points,
        cell_properties={2: {"facies": np.array([3, 7])}},
    )
    write_gmap_vtu(g, tmp_path / "faces.vtu", name="two faces")
    grid = pv.read(tmp_path / "faces.vtu")
    assert grid.n_cells == 2 and list(grid.celltypes) == [pv.CellType.POLYGON, pv.CellType.TRIANGLE]
    assert list(grid.cell_data["facies"]) == [3, 7]
    assert np.isclose(grid.compute_cell_sizes()["Area"].sum(), 1.5)


def test_tetrahedra_and_an_extruded_cube_as_polyhedra(tmp_path: Path) -> None:
    vertices, tetrahedra = block_tetrahedra(2)
    solid = gmaps.GMap.from_tetrahedra(vertices, tetrahedra, cell_properties={"k": np.arange(len(tetrahedra))})
    write_gmap_vtu(solid, tmp_path / "solid.vtu")
    grid = pv.read(tmp_path / "solid.vtu")
    assert grid.n_cells == len(tetrahedra) and set(grid.celltypes) == {pv.CellType.POLYHEDRON}
    assert np.isclose(np.abs(grid.compute_cell_sizes()["Volume"]).sum(), 8.0)  # the 2 x 2 x 2 block
    assert list(grid.cell_data["k"]) == list(range(len(tetrahedra)))
    square = gmaps.GMap.from_polygons([[0, 0], [1, 0], [1, 1], [0, 1]], [[0, 1, 2, 3]])
    cube = gmaps.extrude(square, [0.0, 1.0])
    write_gmap_vtu(cube, tmp_path / "cube.vtu")
    one = pv.read(tmp_path / "cube.vtu")
    assert one.n_cells == 1 and one.get_cell(0).n_faces == 6
    assert np.isclose(abs(one.compute_cell_sizes()["Volume"][0]), 1.0)


def test_extra_axes_become_point_data_and_higher_maps_are_refused(tmp_path: Path) -> None:
    square = gmaps.GMap.from_polygons([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], [[0, 1, 2, 3]])
    history = gmaps.extrude(square, [2019.0, 2021.0])
    write_gmap_vtu(history, tmp_path / "history.vtu", axes=["x", "y", "z", "knowledge"])
    grid = pv.read(tmp_path / "history.vtu")
    assert sorted(set(grid.point_data["knowledge"])) == [2019.0, 2021.0]
    with pytest.raises(tgsis.FileFormatError, match="a 4-G-map has no VTK cells"):
        write_gmap_vtu(gmaps.extrude(history, [0.0, 1.0]), tmp_path / "four.vtu")
    with pytest.raises(tgsis.FileFormatError, match="axes name 2 axes"):
        write_gmap_vtu(history, tmp_path / "bad.vtu", axes=["x", "y"])
