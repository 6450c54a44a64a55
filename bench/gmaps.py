"""n-G-maps in numpy: build and i-cells of a 1M-triangle surface (6M darts) and a 100k-tetrahedron solid.

Meshes: a 1000 x 500 grid of quads split into 1,000,000 triangles (501,501
vertices), and a 26 x 26 x 26 block of cubes split into 6 tetrahedra each
(105,456 tetrahedra, 2,530,944 darts). Timed, medians of ``--repeat`` runs:

- ``GMap.from_triangles`` / ``GMap.from_tetrahedra`` (validation, the
  involutions, alpha_n sewn across shared facets, the GMap's own checks);
- the i-cells of every dimension, from scratch (``orbit_labels``: min-label
  propagation finished by scipy), and the same orbits by
  ``scipy.sparse.csgraph.connected_components`` alone (``rounds=0``);
- ``GMap.check()`` (conditions (i)-(iii) and shared vertices);
- baselines in the same run: trimesh's ``face_adjacency`` of the same
  triangles on a fresh ``Trimesh`` (edges sorted and grouped: the work of
  sewing alpha_2, and what most codes build instead of a G-map), and a
  half-edge structure (twin of each directed edge by sorting, 3M half-edges);
- model 5: extrusion of a 100,000-triangle piece of the surface over 3
  intervals (10.8M darts) and a slice between two layers.

No database here.

    python bench/gmaps.py [--repeat 3]
"""

from __future__ import annotations

import argparse
import platform
from typing import Any

import numpy as np
import numpy.typing as npt
import scipy
import trimesh
from timing import timed

from tgsis.gmaps import GMap, extrude, orbit_labels, slice

IntArray = npt.NDArray[np.int64]


def grid_triangles(nx: int, ny: int) -> tuple[npt.NDArray[np.float64], IntArray]:
    """An nx x ny grid of quads, each split into two triangles: 2 nx ny triangles."""
    x, y = np.meshgrid(np.arange(nx + 1, dtype=float), np.arange(ny + 1, dtype=float), indexing="ij")
    vertices = np.stack([x.ravel(), y.ravel(), np.sin(x.ravel() / 50) * np.cos(y.ravel() / 40)], axis=1)
    i, j = (a.ravel() for a in np.meshgrid(np.arange(nx), np.arange(ny), indexing="ij"))
    a = i * (ny + 1) + j
    b, c, d = a + ny + 1, a + ny + 2, a + 1
    return vertices, np.concatenate([np.stack([a, b, c], axis=1), np.stack([a, c, d], axis=1)]).astype(np.int64)


def block_tetrahedra(n: int) -> tuple[npt.NDArray[np.float64], IntArray]:
    """An n^3 block of unit cubes, 6 tetrahedra each around the main diagonal."""
    m = n + 1
    x, y, z = np.meshgrid(np.arange(m), np.arange(m), np.arange(m), indexing="ij")
    vertices = np.stack([x.ravel(), y.ravel(), z.ravel()], axis=1).astype(float)
    i, j, k = (a.ravel() for a in np.meshgrid(np.arange(n), np.arange(n), np.arange(n), indexing="ij"))
    corner = [((i + a) * m + (j + b)) * m + (k + c) for a in (0, 1) for b in (0, 1) for c in (0, 1)]
    paths = [(0, 1, 3, 7), (0, 1, 5, 7), (0, 2, 3, 7), (0, 2, 6, 7), (0, 4, 5, 7), (0, 4, 6, 7)]
    return vertices, np.concatenate([np.stack([corner[p] for p in path], axis=1) for path in paths]).astype(np.int64)


def all_cells(g: GMap, rounds: int | None = None) -> list[int]:
    """Label the i-cells of every dimension from scratch; their counts."""
    n = g.dimension
    kwargs: dict[str, Any] = {} if rounds is None else {"rounds": rounds}
    return [orbit_labels(g.alpha, [j for j in range(n + 1) if j != i], **kwargs)[1] for i in range(n + 1)]


def half_edges(triangles: IntArray) -> IntArray:
    """Twin of every half-edge (-1 on the border), by sorting the undirected edge keys."""
    tail = triangles.reshape(-1)
    head = np.roll(triangles, -1, axis=1).reshape(-1)
    key = np.minimum(tail, head) * (int(triangles.max()) + 1) + np.maximum(tail, head)
    order = np.argsort(key)
    sorted_key = key[order]
    same = np.flatnonzero(sorted_key[1:] == sorted_key[:-1])
    twin = np.full(len(key), -1, dtype=np.int64)
    twin[order[same]] = order[same + 1]
    twin[order[same + 1]] = order[same]
    return twin


def run(repeat: int) -> dict[str, float]:
    """Build the meshes, check the answers, time everything; print and return the figures."""
    vs, ts = grid_triangles(1000, 500)
    vt, tt = block_tetrahedra(26)
    print(
        f"machine: {platform.machine()}, {platform.python_implementation()} {platform.python_version()}, "
        f"numpy {np.__version__}, scipy {scipy.__version__}, trimesh {trimesh.__version__}"
    )
    print(f"surface: {len(vs)} vertices, {len(ts)} triangles; solid: {len(vt)} vertices, {len(tt)} tetrahedra")

    surface = GMap.from_triangles(vs, ts)
    solid = GMap.from_tetrahedra(vt, tt)
    assert surface.check().ok and solid.check().ok
    surface_counts, solid_counts = all_cells(surface), all_cells(solid)
    assert surface_counts == all_cells(surface, rounds=0) and solid_counts == all_cells(solid, rounds=0)
    assert surface_counts == [1001 * 501, 1000 * 501 + 1001 * 500 + 500_000, 1_000_000]
    assert surface_counts[0] - surface_counts[1] + surface_counts[2] == 1
    assert solid_counts[0] - solid_counts[1] + solid_counts[2] - solid_counts[3] == 1
    print(
        f"2-G-map: {surface.n_darts} darts, cells {surface_counts}; 3-G-map: {solid.n_darts} darts, "
        f"cells {solid_counts}"
    )

    t_build_s = timed(lambda: GMap.from_triangles(vs, ts), repeat)
    t_cells_s = timed(lambda: all_cells(surface), repeat)
    t_cells_s_scipy = timed(lambda: all_cells(surface, rounds=0), repeat)
    t_check_s = timed(lambda: surface.check(), repeat)
    t_trimesh = timed(lambda: trimesh.Trimesh(vs, ts, process=False, validate=False).face_adjacency, repeat)
    t_halfedge = timed(lambda: half_edges(ts), repeat)
    t_build_t = timed(lambda: GMap.from_tetrahedra(vt, tt), repeat)
    t_cells_t = timed(lambda: all_cells(solid), repeat)
    t_cells_t_scipy = timed(lambda: all_cells(solid, rounds=0), repeat)
    t_check_t = timed(lambda: solid.check(), repeat)

    piece = GMap.from_triangles(*grid_triangles(250, 200))
    values = [0.0, 1.0, 2.0, 3.0]
    column = extrude(piece, values)
    assert slice(column, 3, 1.5).same_as(piece) and slice(column, 3, 2.0).same_as(piece)
    t_extrude = timed(lambda: extrude(piece, values), repeat)
    t_slice = timed(lambda: slice(column, 3, 1.5), repeat)

    print(f"from_triangles, 1M triangles ({surface.n_darts} darts):   {t_build_s:6.3f} s")
    print(f"  i-cells, all three dimensions:                {t_cells_s:6.3f} s")
    print(
        f"  i-cells by connected_components alone:        {t_cells_s_scipy:6.3f} s  "
        f"({t_cells_s / t_cells_s_scipy:.2f}x)"
    )
    print(f"  check():                                       {t_check_s:6.3f} s")
    print(f"  baseline: trimesh face_adjacency (fresh mesh): {t_trimesh:6.3f} s  (build {t_build_s / t_trimesh:.2f}x)")
    print(
        f"  baseline: half-edge twins by sorting:          {t_halfedge:6.3f} s  (build {t_build_s / t_halfedge:.2f}x)"
    )
    print(f"from_tetrahedra, {len(tt)} tetrahedra ({solid.n_darts} darts): {t_build_t:6.3f} s")
    print(f"  i-cells, all four dimensions:                 {t_cells_t:6.3f} s")
    print(
        f"  i-cells by connected_components alone:        {t_cells_t_scipy:6.3f} s  "
        f"({t_cells_t / t_cells_t_scipy:.2f}x)"
    )
    print(f"  check():                                       {t_check_t:6.3f} s")
    print(
        f"extrude {len(piece.cell_darts(2))} triangles over 3 intervals ({column.n_darts} darts): "
        f"{t_extrude:6.3f} s; slice between layers: {t_slice:6.3f} s"
    )
    return {
        "triangles_build_s": round(t_build_s, 3),
        "triangles_cells_s": round(t_cells_s, 3),
        "triangles_cells_vs_scipy": round(t_cells_s / t_cells_s_scipy, 2),
        "triangles_check_s": round(t_check_s, 3),
        "triangles_build_vs_trimesh_face_adjacency": round(t_build_s / t_trimesh, 2),
        "triangles_build_vs_half_edges": round(t_build_s / t_halfedge, 2),
        "tetrahedra_build_s": round(t_build_t, 3),
        "tetrahedra_cells_s": round(t_cells_t, 3),
        "tetrahedra_cells_vs_scipy": round(t_cells_t / t_cells_t_scipy, 2),
        "tetrahedra_check_s": round(t_check_t, 3),
        "extrude_s": round(t_extrude, 3),
        "slice_s": round(t_slice, 3),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--repeat", type=int, default=3)
    figures = run(parser.parse_args().repeat)
    for name, value in figures.items():
        print(f"{name}: {value}")


if __name__ == "__main__":
    main()
