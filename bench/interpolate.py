"""Morphological interpolation of a 100k-vertex surface: time per stage (no database).

Source: a bumpy rectangle [0, 4000] x [0, 2000] m as a regular grid of about
100k vertices (317 x 317 by default). Target: a dome over the same
rectangle, Delaunay-triangulated from about 25k scattered points (another
topology). Four corner control pairs, m = 10 instants, tolerance ε = 5 m, and the
source's western border attached to a vertical wall (a controlling surface),
so that the interior trajectories are solved step by step (without any
attachment the spec makes every trajectory linear).
Stages as :func:`tgsis.interpolation.interpolate` times them (cut,
partition, compatible mesh with refinement, trajectories, evolving surface),
and the whole call; the baseline in the same run is one mean-value
parameterisation of the source (``parameterize_patch``), the unit of work
every stage builds on.

    python bench/interpolate.py [--side 317] [--target-points 25000] [--steps 10] [--tolerance 5]
"""

from __future__ import annotations

import argparse
import time

import numpy as np
from scipy.spatial import Delaunay

import tgsis
from tgsis.interpolation import Attachment, InterpolationSetup, interpolate, parameterize_patch


def bumpy_grid(side: int) -> tgsis.Surface:
    u, v = np.meshgrid(np.linspace(0, 4000, side), np.linspace(0, 2000, side))
    z = 30 * np.sin(u / 170) * np.cos(v / 230)
    idx = np.arange(side * side).reshape(side, side)
    a, b, c, d = idx[:-1, :-1].ravel(), idx[:-1, 1:].ravel(), idx[1:, :-1].ravel(), idx[1:, 1:].ravel()
    return tgsis.Surface(
        np.stack([u.ravel(), v.ravel(), z.ravel()], 1),
        np.concatenate([np.stack([a, b, d], 1), np.stack([a, d, c], 1)]),
        name="bumpy",
    )


def dome(points: int, seed: int = 1) -> tgsis.Surface:
    rng = np.random.default_rng(seed)
    per_side = max(8, int(np.sqrt(points) / 2))
    s = np.linspace(0, 1, per_side + 1)[:-1]
    border = np.concatenate(
        [
            np.stack([4000 * s, 0 * s], 1),
            np.stack([4000 + 0 * s, 2000 * s], 1),
            np.stack([4000 * (1 - s), 2000 + 0 * s], 1),
            np.stack([0 * s, 2000 * (1 - s)], 1),
        ]
    )
    inside = rng.random((points - len(border), 2)) * [3980, 1980] + 10
    xy = np.concatenate([border, inside])
    z = 600 * np.exp(-((xy[:, 0] - 2000) ** 2 + (xy[:, 1] - 1000) ** 2) / 600**2)
    tri = Delaunay(xy).simplices
    e1, e2 = xy[tri[:, 1]] - xy[tri[:, 0]], xy[tri[:, 2]] - xy[tri[:, 0]]
    flip = e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0] < 0
    tri[flip] = tri[flip][:, [0, 2, 1]]
    return tgsis.Surface(np.column_stack([xy, z]), tri, name="dome")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--side", type=int, default=317)
    parser.add_argument("--target-points", type=int, default=25_000)
    parser.add_argument("--steps", type=int, default=10)
    parser.add_argument("--tolerance", type=float, default=5.0)
    args = parser.parse_args()

    source, target = bumpy_grid(args.side), dome(args.target_points)
    side = args.side
    source_corners = (0, side - 1, side * side - 1, side * (side - 1))
    per_side = max(8, int(np.sqrt(args.target_points) / 2))
    target_corners = (0, per_side, 2 * per_side, 3 * per_side)
    print(
        f"source: {source.n_vertices} vertices, {source.n_cells} triangles; target: {target.n_vertices} vertices, "
        f"{target.n_cells} triangles; m = {args.steps}, tolerance {args.tolerance} m"
    )
    start = time.perf_counter()
    parameterize_patch(source.vertices, source.cells, np.array(source_corners))
    baseline = time.perf_counter() - start
    wall = tgsis.Surface([[0, -100, -1000], [0, 2100, -1000], [0, 2100, 1000], [0, -100, 1000]], [[0, 1, 2], [0, 2, 3]])
    west = tuple(Attachment(side * j, ("west",)) for j in range(side))
    setup = InterpolationSetup(
        source_corners,
        target_corners,
        steps=args.steps,
        tolerance=args.tolerance,
        controlling_surfaces={"west": "west"},
        attachments=west,
    )
    start = time.perf_counter()
    result = interpolate(source, target, setup, 0.0, 1.0, name="bench", surfaces={"west": wall})
    total = time.perf_counter() - start
    print(f"baseline: one mean-value parameterisation of the source: {baseline:.2f} s")
    for stage, seconds in result.timings.items():
        print(f"  {stage}: {seconds:.2f} s")
    print(
        f"interpolate: {total:.2f} s ({total / baseline:.1f} parameterisations); {result.source.n_vertices} "
        f"vertices after refinement, error {result.error:.3g} m"
    )
    print(f"parameterize_s: {baseline:.3f}")
    for stage, seconds in result.timings.items():
        print(f"{stage}_s: {seconds:.3f}")
    print(f"interpolate_s: {total:.3f}")
    print(f"interpolate_vs_parameterize: {total / baseline:.2f}")


if __name__ == "__main__":
    main()
