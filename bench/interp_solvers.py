"""Sparse solves of morphological interpolation at ~100k vertices (no database).

Measures, on a Delaunay-triangulated random disk (bumpy source, twisted dome as
compatible target):

* the mean-value parameterisation: weights, assembly, and the two solves with
  several SuperLU set-ups;
* the interior solves of m = 10 trajectory samples (8 intermediate steps):
  a fresh SuperLU factorisation per step (what tgsis does), the same with the
  column ordering of the first step reused, and BiCGSTAB warm-started from the
  previous step and preconditioned by one factorisation at s = 1/2 (GMRES
  the same way took twice as many preconditioner solves), step by step
  interleaved so that a busy machine slows all three alike.

Run: ``python bench/interp_solvers.py [n]`` (default n = 100000).
"""

from __future__ import annotations

import sys
import time

import numpy as np
from scipy.sparse import csc_matrix
from scipy.sparse.linalg import LinearOperator, bicgstab, splu
from scipy.spatial import Delaunay

from tgsis.interpolation._arrays import interior_mask as vertices_inside
from tgsis.interpolation.parameterize import (WeightPattern, _chord_border, _ordered_border,
                                              _split_system, border_loop, compatible_patch, mean_value_data,
                                              sparse_solve)
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
            "permc_spec": "MMD_AT_PLUS_A", "diag_pivot_thresh": 0.0, "options": {"SymmetricMode": True}},
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
    system = clock("trajectory set-up (pattern, both weight sets)",
                   lambda: InteriorSteps(xyz, target, tri, interior_mask), results)
    bpos = [xyz[system.border] + (j / (steps - 1)) * (target[system.border] - xyz[system.border])
            for j in range(steps)]

    plain = InteriorSteps(xyz, target, tri, interior_mask)  # never solved through .solve: not reordered
    # the three ways step by step, interleaved, so that a busy machine slows them alike
    fresh_time = reuse_time = krylov_time = 0.0
    mid, _ = plain.matrix(0.5)
    start = time.perf_counter()
    mid_lu = splu(mid, permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0, options={"SymmetricMode": True})
    krylov_time += time.perf_counter() - start
    q = mid.shape[0]
    precond = LinearOperator((q, q), matvec=mid_lu.solve)
    previous = xyz[system.interior].copy()
    iterations = 0
    worst_reuse = worst_krylov = 0.0
    for j in range(1, steps - 1):
        s = j / (steps - 1)
        start = time.perf_counter()
        mat, rhs_b = plain.matrix(s)
        exact = sparse_solve(mat, rhs_b @ bpos[j])
        fresh_time += time.perf_counter() - start

        start = time.perf_counter()
        got = system.solve(s, bpos[j])  # what tgsis does: the first step orders, the others reuse it
        reuse_time += time.perf_counter() - start
        worst_reuse = max(worst_reuse, float(np.abs(got - exact).max()))

        start = time.perf_counter()
        mat, rhs_b = plain.matrix(s)
        rhs_j = rhs_b @ bpos[j]
        x = np.empty_like(rhs_j)
        for k in range(3):
            count = [0]

            def tick(_: object, count: list[int] = count) -> None:
                count[0] += 1

            x[:, k], info = bicgstab(mat, rhs_j[:, k], x0=previous[:, k], M=precond, rtol=1e-12, atol=0.0,
                                     callback=tick)
            assert info == 0, info
            iterations += count[0]
        previous = x
        krylov_time += time.perf_counter() - start
        worst_krylov = max(worst_krylov, float(np.abs(x - exact).max()))
    results[f"m={steps}: SuperLU ordered afresh (MMD_AT_PLUS_A, diagonal pivots) every step"] = fresh_time
    results[f"m={steps}: SuperLU, ordering of the first step reused (tgsis)"] = reuse_time
    results[f"m={steps}: BiCGSTAB rtol 1e-12, warm start, preconditioned by one SuperLU at s=1/2"] = krylov_time
    print(f"BiCGSTAB: {iterations} iterations over {steps - 2} steps x 3 coordinates; largest difference from "
          f"fresh SuperLU {worst_krylov:.1e} (ordering reused: {worst_reuse:.1e})")

    # end to end: the trajectories call (interior solved) and a compatible patch onto a 20k-vertex dome
    clock(f"vertex_trajectories(), m={steps}, interior solved", lambda: vertex_trajectories(
        xyz, target, tri, steps, interior_method="solve"), results)
    dome_xyz, dome_tri, dome_controls = disk(20_000, seed=1)
    dome_xyz[:, 2] = 0.5 * (1 - (dome_xyz[:, :2] ** 2).sum(axis=1))
    patch = clock(f"compatible_patch() of the {len(xyz)}-vertex disk onto a 20k dome, tolerance 2e-4",
                  lambda: compatible_patch(xyz, tri, controls, dome_xyz, dome_tri, dome_controls, tolerance=2e-4),
                  results)
    print(f"   {patch.rounds} refinement rounds, {len(patch.source_vertices) - len(xyz)} vertices added, "
          f"error {patch.error:.2g}")
    for label, value in results.items():
        print(f"{label}: {value:.3f}")


if __name__ == "__main__":
    main()
