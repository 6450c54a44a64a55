"""Sparse solves of morphological interpolation at ~100k vertices (no database).

Measures, on a Delaunay-triangulated random disk (bumpy source, twisted dome as
compatible target):

* the mean-value parameterisation: weights, assembly, and the two solves with
  several SuperLU set-ups;
* the interior solves of m = 10 trajectory samples (8 intermediate steps):
  a fresh SuperLU factorisation per step (what tgsis does), the same with the
  column ordering of the first step reused, and GMRES / BiCGSTAB warm-started
  from the previous step and preconditioned by one factorisation at s = 1/2.

Run: ``python bench/interp_solvers.py [n]`` (default n = 100000).
"""

from __future__ import annotations

import sys
import time

import numpy as np
from scipy.sparse import csc_matrix
from scipy.sparse.linalg import LinearOperator, bicgstab, gmres, splu
from scipy.spatial import Delaunay

from tgsis.interpolation.parameterize import (WeightPattern, _chord_border, _interior_mask, _ordered_border,
                                              _split_system, border_loop, mean_value_data)
from tgsis.interpolation.trajectories import InteriorSteps


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
    interior_mask = _interior_mask(tri, len(xyz))
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

    def fresh() -> list[np.ndarray]:
        return [system.solve(j / (steps - 1), bpos[j]) for j in range(1, steps - 1)]

    exact = clock(f"m={steps}: fresh SuperLU (MMD_AT_PLUS_A, diagonal pivots) per step", fresh, results)

    def reuse_ordering() -> list[np.ndarray]:
        out = []
        perm = None
        for j in range(1, steps - 1):
            mat, rhs_b = system.matrix(j / (steps - 1))
            rhs_j = rhs_b @ bpos[j]
            if perm is None:
                lu = splu(mat, permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0, options={"SymmetricMode": True})
                perm = np.argsort(lu.perm_c)
                out.append(lu.solve(rhs_j))
                continue
            permuted = csc_matrix(mat[perm][:, perm])
            lu = splu(permuted, permc_spec="NATURAL", diag_pivot_thresh=0.0, options={"SymmetricMode": True})
            x = np.empty_like(rhs_j)
            x[perm] = lu.solve(rhs_j[perm])
            out.append(x)
        return out

    got = clock(f"m={steps}: SuperLU, ordering of step 2 reused", reuse_ordering, results)
    print(f"   max difference from fresh: {max(np.abs(g - e).max() for g, e in zip(got, exact)):.2e}")

    def krylov(method) -> list[np.ndarray]:  # type: ignore[no-untyped-def]
        mid, _ = system.matrix(0.5)
        lu = splu(mid, permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0, options={"SymmetricMode": True})
        q = mid.shape[0]
        precond = LinearOperator((q, q), matvec=lu.solve)
        out = []
        previous = xyz[system.interior].copy()
        iterations = 0
        for j in range(1, steps - 1):
            mat, rhs_b = system.matrix(j / (steps - 1))
            rhs_j = rhs_b @ bpos[j]
            x = np.empty_like(rhs_j)
            for k in range(3):
                count = [0]

                def tick(_: object, count: list[int] = count) -> None:
                    count[0] += 1

                extra = {"callback_type": "pr_norm"} if method is gmres else {}
                x[:, k], info = method(mat, rhs_j[:, k], x0=previous[:, k], M=precond, rtol=1e-12, atol=0.0,
                                       callback=tick, **extra)
                iterations += count[0]
                assert info == 0, info
            previous = x
            out.append(x)
        print(f"   {iterations} iterations over {steps - 2} steps x 3 coordinates")
        return out

    for label, method in (("GMRES", gmres), ("BiCGSTAB", bicgstab)):
        got = clock(f"m={steps}: {label}, warm start, preconditioned by one SuperLU at s=1/2",
                    lambda method=method: krylov(method), results)
        print(f"   max difference from fresh: {max(np.abs(g - e).max() for g, e in zip(got, exact)):.2e}")
    for label, value in results.items():
        print(f"{label}: {value:.3f}")


if __name__ == "__main__":
    main()
