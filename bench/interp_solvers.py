"""Sparse solves of morphological interpolation at ~100k vertices (no database).

Measures, on a Delaunay-triangulated random disk (bumpy source, twisted dome as
compatible target):

* the mean-value parameterisation: weights, assembly, and the two solves with
  several SuperLU set-ups;
* the interior solves of m = 10 trajectory samples: tgsis's one
  factorisation of I - Λ̄_II (the mean of the two meshes' mean value weights)
  for all steps, each step a triangular solve pair, against the source
  design's rule, which needs a fresh factorisation per step (its weights
  change with time; what tgsis did before issue 37), interleaved so that a
  busy machine slows both alike; and SuperLU's solve of the 30 right-hand
  sides at once against three at a time.

Run: ``python bench/interp_solvers.py [n]`` (default n = 100000).
"""

from __future__ import annotations

import sys
import time

import numpy as np
from scipy.sparse import csc_matrix
from scipy.sparse.linalg import splu
from scipy.spatial import Delaunay

from tgsis.interpolation._arrays import interior_mask as vertices_inside
from tgsis.interpolation.parameterize import (
    WeightPattern,
    _chord_border,
    _ordered_border,
    _split_system,
    border_loop,
    compatible_patch,
    mean_value_data,
    sparse_solve,
)
from tgsis.interpolation.trajectories import InteriorSteps, vertex_trajectories


def disk(n: int, seed: int = 0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    rim = int(4 * np.sqrt(n))
    angle = 2 * np.pi * np.arange(rim) / rim
    r = np.sqrt(rng.random(n - rim)) * 0.995
    theta = 2 * np.pi * rng.random(n - rim)
    xy = np.concatenate([np.c_[np.cos(angle), np.sin(angle)], np.c_[r * np.cos(theta), r * np.sin(theta)]])
    tri = Delaunay(xy).simplices.astype(np.int64)
    e1, e2 = xy[tri[:, 1]] - xy[tri[:, 0]], xy[tri[:, 2]] - xy[tri[:, 0]]
    area = e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0]
    tri[area < 0] = tri[area < 0][:, ::-1]
    z = 0.05 * np.sin(7 * xy[:, 0]) * np.cos(5 * xy[:, 1])
    return np.c_[xy, z], tri, np.arange(0, rim, rim // 4)[:4]


def clock(label: str, action, results: dict[str, float]):  # type: ignore[no-untyped-def]
    start = time.perf_counter()
    value = action()
    results[label] = time.perf_counter() - start
    print(f"{label}: {results[label]:.3f} s", flush=True)
    return value


def main() -> None:
    n = int(sys.argv[1]) if len(sys.argv) > 1 else 100_000
    xyz, tri, controls = disk(n)
    results: dict[str, float] = {}
    print(f"disk: {len(xyz)} vertices, {len(tri)} triangles")
    loop = clock("border loop", lambda: border_loop(tri, len(xyz)), results)
    border = _ordered_border(loop, controls, len(xyz))
    interior_mask = vertices_inside(tri, len(xyz))
    pattern = clock("pattern (CSR structure)", lambda: WeightPattern.of(tri, len(xyz)), results)
    lam = clock("mean value weights", lambda: mean_value_data(xyz, tri, pattern, interior_mask), results)
    interior = np.flatnonzero(interior_mask)
    uvb = _chord_border(xyz, border, controls)
    a, b = clock("assembly of I - λ_II, λ_IB", lambda: _split_system(pattern.matrix(lam), interior, border), results)
    rhs = b @ uvb
    print(f"unknowns {a.shape[0]}, non-zeros {a.nnz}")
    setups = {
        "SuperLU default (COLAMD)": {},
        "SuperLU MMD_AT_PLUS_A, partial pivoting": {"permc_spec": "MMD_AT_PLUS_A"},
        "SuperLU MMD_AT_PLUS_A, diagonal pivots, symmetric mode": {
            "permc_spec": "MMD_AT_PLUS_A",
            "diag_pivot_thresh": 0.0,
            "options": {"SymmetricMode": True},
        },
    }
    reference = None
    if len(xyz) > 30_000:  # row pivoting spoils the ordering: 15 s at 20k vertices already
        del setups["SuperLU MMD_AT_PLUS_A, partial pivoting"]
    for label, options in setups.items():
        uv = clock(f"param solve u,v: {label}", lambda o=options: splu(csc_matrix(a), **o).solve(rhs), results)
        reference = uv if reference is None else reference
        print(f"   max difference from the first: {np.abs(uv - reference).max():.2e}")

    # trajectories: compatible target = twisted dome, same topology
    r2 = (xyz[:, :2] ** 2).sum(axis=1)
    twist = 0.6 * (1 - r2)
    c, s = np.cos(twist), np.sin(twist)
    target = np.c_[c * xyz[:, 0] - s * xyz[:, 1], s * xyz[:, 0] + c * xyz[:, 1], 0.5 * (1 - r2)]
    steps = 10
    weights = np.arange(steps) / (steps - 1)
    system = clock(
        "trajectory set-up: both weight sets, I - mean weights, one factorisation (tgsis)",
        lambda: InteriorSteps(xyz, target, tri, interior_mask),
        results,
    )
    first, last = xyz[system.border], target[system.border]
    # the border's straight paths, bent off them in between as a controlling surface would
    bend = (
        0.01 * np.sin(np.pi * weights)[:, None, None] * np.sin(3 * np.arctan2(first[:, 1], first[:, 0]))[None, :, None]
    )
    bpos = first[None] + weights[:, None, None] * (last - first)[None] + bend
    lam_first = mean_value_data(xyz, tri, pattern, interior_mask)
    lam_last = mean_value_data(target, tri, pattern, interior_mask)

    def design_step(j: int) -> np.ndarray:
        """The source design's rule: convex combinations with weights interpolated in time, a factorisation each."""
        mat, rhs_b = _split_system(
            pattern.matrix(lam_first + weights[j] * (lam_last - lam_first)), interior, system.border
        )
        return sparse_solve(mat, rhs_b @ bpos[j])

    ours_time = design_time = 0.0
    for j in range(steps):  # interleaved, step by step; the design's first and last steps are its given shapes
        start = time.perf_counter()
        system.solve(weights[j : j + 1], bpos[j : j + 1])
        ours_time += time.perf_counter() - start
        if 0 < j < steps - 1:
            start = time.perf_counter()
            design_step(j)
            design_time += time.perf_counter() - start
    results[f"m={steps}: every step from the one factorisation (tgsis), solves only"] = ours_time
    results[f"m={steps}: the design's rule, a fresh SuperLU (MMD_AT_PLUS_A) per intermediate step"] = design_time
    lu = system._lu
    assert lu is not None
    columns = np.asfortranarray(np.random.default_rng(0).random((len(system.solved), 3 * steps)))
    clock(f"SuperLU solve of {3 * steps} right-hand sides at once", lambda: lu.solve(columns), results)
    clock(
        f"SuperLU solves of {3 * steps} right-hand sides three at a time (tgsis)",
        lambda: [lu.solve(np.asfortranarray(columns[:, k : k + 3])) for k in range(0, 3 * steps, 3)],
        results,
    )

    # end to end: the trajectories call (interior solved) and a compatible patch onto a 20k-vertex dome
    clock(
        f"vertex_trajectories(), m={steps}, interior solved",
        lambda: vertex_trajectories(xyz, target, tri, steps, interior_method="solve"),
        results,
    )
    dome_xyz, dome_tri, dome_controls = disk(20_000, seed=1)
    dome_xyz[:, 2] = 0.5 * (1 - (dome_xyz[:, :2] ** 2).sum(axis=1))
    patch = clock(
        f"compatible_patch() of the {len(xyz)}-vertex disk onto a 20k dome, tolerance 2e-4",
        lambda: compatible_patch(xyz, tri, controls, dome_xyz, dome_tri, dome_controls, tolerance=2e-4),
        results,
    )
    print(
        f"   {patch.rounds} refinement rounds, {len(patch.source_vertices) - len(xyz)} vertices added, "
        f"error {patch.error:.2g}"
    )
    for label, value in results.items():
        print(f"{label}: {value:.3f}")


if __name__ == "__main__":
    main()
